"""``tools/training_order.py`` (docs/costs.md runs it): the profiler's training order of a shader,
printed without rendering; on the IBL shader the final colour comes first."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from safety_cli import env

ROOT = Path(__file__).resolve().parents[1]


def test_the_ibl_shader_trains_its_final_colour_first():
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "training_order.py"), "shaders/ibl_gltf.glsl",
                        "sessions/ibl.json", "--top", "3", "--json", "--find", "u_GGXEnvSampler"],
                       cwd=ROOT, env=env(), capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    assert [r["rank"] for r in doc["order"]] == [1, 2, 3]
    assert doc["order"][0]["final"] and doc["order"][0]["text"] == "vec4(toneMap(color), 1.0)"
    assert doc["trained"] + doc["too_cheap"] == doc["listed"]
    assert 1 < doc["found"]["u_GGXEnvSampler"] <= doc["trained"]
