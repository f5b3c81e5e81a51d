"""Random and mutated session JSON: load_session succeeds or raises SessionError, nothing else."""
import copy
import json
import os
import tempfile

import numpy as np
from hypothesis import HealthCheck, given, settings, strategies as st

from rrcache.errors import SessionError
from rrcache.session import load_session

RICH = {
    "rrcache_session": 1, "name": "fuzz", "resolution": [16, 8], "frames": 6, "fps": 24,
    "background": [0, 0, 0, 1],
    "camera": {"fov": 50, "near": 0.5, "far": 20,
               "keyframes": [{"frame": 0, "eye": [0, 1, 4], "target": [0, 0, 0], "up": [0, 1, 0]},
                             {"frame": 5, "eye": [4, 1, 0]}]},
    "light": {"color": [1, 0.9, 0.8], "orbit": {"center": [0, 0, 0], "radius": 5, "height": 3,
                                                "degrees_per_frame": 2, "start_degrees": 10}},
    "objects": [
        {"name": "ball", "procedural": {"type": "icosphere", "radius": 0.5, "subdivisions": 1},
         "keyframes": [{"frame": 0, "translate": [0, 0, 0], "rotate": [0, 0, 1, 0], "scale": 1},
                       {"frame": 5, "translate": [1, 0, 0], "rotate": [90, 1, 0, 0], "scale": [1, 2, 1]}]},
        {"procedural": {"type": "revolve", "profile": [[0, 0], [0.4, 0], [0.2, 1], [0, 1.1]], "segments": 6}},
        {"procedural": {"type": "torus_knot", "segments": 24, "tube_segments": 4}},
        {"procedural": {"type": "cylinder", "segments": 5}},
    ],
    "uniforms": {"u_shininess": 32.0, "u_n": 3, "u_on": True, "u_color": [1, 0, 0],
                 "u_m": [[1, 0], [0, 1]],
                 "u_wave": {"keyframes": [{"frame": 0, "value": 0.0}, {"frame": 5, "value": 1.0}]}},
}

scalars = st.one_of(st.none(), st.booleans(), st.integers(-5, 300),
                    st.floats(-1e6, 1e6, allow_nan=False), st.text(max_size=6),
                    st.sampled_from(["torus", "box", "plane", "cube", "2d", "frame", "keyframes", "eye"]))
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=5),
                                                       st.dictionaries(st.text(max_size=8), inner, max_size=4)),
                      max_leaves=12)


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


@st.composite
def mutated(draw):
    doc = copy.deepcopy(RICH)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "delete", "add", "number"]))
        if action == "replace":
            parent[path[-1]] = draw(values)
        elif action == "delete":
            del parent[path[-1]]
        elif action == "number" and isinstance(parent[path[-1]], (int, float)) and not isinstance(parent[path[-1]], bool):
            parent[path[-1]] = draw(st.one_of(st.integers(-3, 3), st.floats(-3, 3, allow_nan=False)))
        elif isinstance(parent[path[-1]], dict):
            parent[path[-1]][draw(st.text(max_size=8))] = draw(values)
    return json.dumps(doc)


@st.composite
def corrupted_text(draw):
    text = json.dumps(RICH)
    i = draw(st.integers(0, len(text) - 1))
    return text[:i] + draw(st.text(max_size=3)) + text[i + draw(st.integers(0, 3)):]


def _exercise(text: str) -> None:
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "s.json")
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        try:
            s = load_session(path)
        except SessionError as e:
            assert str(e).startswith(path)
            return
        for frame in (0, 3, s.frames - 1):
            assert s.camera_at(frame).view.shape == (4, 4)
            assert s.camera_at(frame).projection(s.aspect).shape == (4, 4)
            s.light_at(frame)
            s.uniform_values(frame)
            for o in s.objects:
                assert o.model_matrix(frame).shape == (4, 4)
        assert len(s.hash) == 64


def test_rich_base_document_loads():
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "s.json")
        with open(path, "w") as f:
            json.dump(RICH, f)
        s = load_session(path)
        assert len(s.objects) == 4 and np.isfinite(s.camera_at(2).view).all()


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_sessions_load_or_raise_session_error(text):
    _exercise(text)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(corrupted_text(), values.map(json.dumps)))
def test_corrupted_text_and_random_json(text):
    _exercise(text)
