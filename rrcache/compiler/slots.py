"""Where the ``slots`` history of amortized sampling fits: the one rule the compiler
(:func:`rrcache.compiler.amortize.instance_amortized`), the profiler and the models share, and the
payload formats of an amortized choice.
"""
from __future__ import annotations

from typing import Optional

#: the payload formats of an amortized choice: 32- or 16-bit floats, or ``u8`` (the slots in 8 bits
#: by the range of the estimator's terms, rrcache.compiler.payload_encoding)
AMORTIZE_PAYLOADS = ("f4", "f2", "u8")

#: the components one payload texel holds (RGBA)
PAYLOAD_COMPONENTS = 4


def slots_fit(total: int, samples: int, components: int, phase: str = "frame") -> Optional[str]:
    """Why the ``slots`` history cannot amortize an estimator of ``total`` (N) terms whose
    accumulators have ``components`` payload components at ``samples`` (m) per frame, or None
    when it can: it needs the ``frame`` phase, m < N dividing N, and room for the N/m subset sums
    in the payload ((N/m) × components ≤ 4). The one rule the compiler
    (:func:`rrcache.compiler.amortize.instance_amortized`), the profiler and the models share.

    >>> slots_fit(16, 4, 1) is None, slots_fit(16, 8, 2) is None
    (True, True)
    >>> print(slots_fit(16, 2, 1))
    the slots history keeps N/m = 8 sums of 1 component(s): more than the payload's 4
    >>> slots_fit(16, 16, 1)
    'the slots history needs m < N dividing N (N = 16, m = 16)'
    """
    n, m, c = int(total), int(samples), int(components)
    if phase != "frame":
        return f"the slots history needs the 'frame' phase, not {phase!r}"
    if m < 1 or m >= n or n % m:
        return f"the slots history needs m < N dividing N (N = {n}, m = {m})"
    if (n // m) * c > PAYLOAD_COMPONENTS:
        return (f"the slots history keeps N/m = {n // m} sums of {c} component(s): more than the payload's "
                f"{PAYLOAD_COMPONENTS}")
    return None


def slots_samples(total: int, components: int) -> list[int]:
    """The m at which the ``slots`` history fits (:func:`slots_fit`), smallest first.

    >>> slots_samples(16, 1), slots_samples(16, 2), slots_samples(12, 1), slots_samples(5, 1)
    ([4, 8], [8], [3, 4, 6], [])
    """
    return [m for m in range(1, int(total)) if slots_fit(total, m, components) is None]
