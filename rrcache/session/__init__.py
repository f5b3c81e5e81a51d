"""Session loading: a JSON session file (docs/design.md §4b) → a validated :class:`Session`.

>>> from rrcache.session import load_session
>>> s = load_session("tests/data/sessions/minimal.json")
>>> s.camera_at(0).projection(s.aspect).shape
(4, 4)
"""
from rrcache.session.loader import load_session
from rrcache.session.model import Camera, Light, MeshData, SceneObject, Session, TextureAsset
from rrcache.session.procedural import make_mesh

__all__ = ["load_session", "Session", "MeshData", "SceneObject", "Camera", "Light", "TextureAsset", "make_mesh"]
