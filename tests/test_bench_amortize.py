"""rrcache bench-amortize on the temple at a tiny size: the figures are there and consistent."""
from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from rrcache.cli import cli

ROOT = Path(__file__).resolve().parent.parent


def test_bench_amortize_json_and_images(gl_ctx, tmp_path):
    out = CliRunner().invoke(cli, [
        "bench-amortize", str(ROOT / "shaders" / "pcf_shadows.glsl"), str(ROOT / "sessions" / "temple.json"),
        "--estimator", "e1", "--samples", "4", "--lambda", "0.6", "--reference", "PCF_SAMPLES=64",
        "--also", "PCF_SAMPLES=1", "--frames", "4", "--repeats", "2", "--error-every", "2",
        "--resolution", "64x48", "--images", str(tmp_path), "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.output[out.output.index("{"):])
    assert (doc["samples"], doc["of"], doc["lambda"], doc["repeats"]) == (4, 16, 0.6, 2)
    assert doc["error_frames"] == 2 and 0 < doc["original_error"] and 0 < doc["amortized_error"]
    assert doc["speedup_range"][0] <= doc["speedup"] <= doc["speedup_range"][1]
    assert doc["original_cpu_ms"] > 0 and doc["amortized_cpu_ms"] > 0
    assert sorted(doc["images"]) == ["also", "amortized", "comparison", "original", "reference"]
    assert all(Path(p).stat().st_size > 100 for p in doc["images"].values())
    # the labelled figure: four columns (1 sample, 16, amortized, reference), two rows
    import OpenImageIO as oiio

    spec = oiio.ImageInput.open(doc["images"]["comparison"]).spec()
    assert spec.width > 4 * 64 and spec.height > 64


def test_bench_amortize_unknown_estimator(tmp_path):
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-m", "rrcache", "bench-amortize",
                          str(ROOT / "shaders" / "pcf_shadows.glsl"), str(ROOT / "sessions" / "temple.json"),
                          "--estimator", "e9", "--reference", "PCF_SAMPLES=64", "--frames", "2"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "e9" in lines[0] and "pcf_shadows.glsl" in lines[0]


def test_instance_writes_an_amortized_variant(tmp_path):
    out = CliRunner().invoke(cli, [
        "instance", str(ROOT / "shaders" / "pcf_shadows.glsl"), "--session", str(ROOT / "sessions" / "temple.json"),
        "--estimator", "e1", "--samples", "4", "--lambda", "0.6", "--algorithm", "two-pass", "--out", str(tmp_path)])
    assert out.exit_code == 0, out.output
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["amortized"]["cycle"] == 4 and manifest["algorithm"] == "two-pass"
    assert sorted(manifest["passes"]) == ["hit", "hit@1", "hit@2", "hit@3", "miss"]
    assert "rr_lambda" in (tmp_path / "hit@2.frag").read_text()
    both = CliRunner().invoke(cli, ["instance", str(ROOT / "shaders" / "pcf_shadows.glsl"), "--out", str(tmp_path)])
    assert both.exit_code == 2 and "--node or --estimator" in both.output


def test_the_comparison_window_is_where_the_image_differs_most(tmp_path):
    """The magnified window follows the chosen panel's error, and each caption's error is the
    panel's mean RGB distance from the reference."""
    import numpy as np

    from rrcache.bench.amortize_sheet import noisiest_window, write_sheet

    ref = np.zeros((40, 60, 4), np.float32)
    ref[..., 3] = 1.0
    a, b = ref.copy(), ref.copy()
    a[30:40, 50:60, :3] = 0.3        # a's error sits bottom right
    b[0:10, 0:10, :3] = 0.6          # b's top left
    assert noisiest_window(a, ref, 10) == (30, 50) and noisiest_window(b, ref, 10) == (0, 0)
    out = write_sheet(str(tmp_path / "sheet.png"), [("a", a), ("b", b)], ref, crop=10, window_of=1)
    assert out["window"] == [0, 0, 10]
    expect_a = 100 * np.sqrt(3 * 0.3 ** 2) / (40 * 60)
    assert abs(out["errors"]["a"] - expect_a) < 1e-6 and out["errors"]["b"] > out["errors"]["a"]
    assert (tmp_path / "sheet.png").stat().st_size > 1000
