"""Benchmarks (`rrcache bench-*`): timings reported as numbers and ratios, never asserted in tests."""
