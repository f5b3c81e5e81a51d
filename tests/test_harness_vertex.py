"""The generated vertex shader and the mesh defines (text only; linking is covered by the renderer tests)."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from rrcache.errors import SourceLoc, UnsupportedShaderError
from rrcache.compiler.vertex import mesh_attributes, mesh_defines, session_attributes, vertex_source


def test_only_declared_varyings_are_written():
    src = vertex_source({"v_texcoord": "vec2"})
    assert "out vec2 v_texcoord;" in src and "v_texcoord = a_texcoord;" in src
    assert "v_normal" not in src and "a_normal" not in src and "rr_prevClip" not in src
    assert src.startswith("#version 330 core\n")


def test_prev_clip_uses_previous_mvp():
    src = vertex_source({"rr_prevClip": "vec4"})
    assert "uniform mat4 u_prevModelViewProjectionMatrix;" in src
    assert "rr_prevClip = u_prevModelViewProjectionMatrix * vec4(a_position, 1.0);" in src


def test_size_conversions():
    src = vertex_source({"v_position": "vec3", "v_objectPosition": "vec4", "v_texcoord": "vec4", "v_color": "float"})
    assert "v_position = (rr_world).xyz;" in src
    assert "v_objectPosition = vec4(a_position, 1.0);" in src
    assert "v_texcoord = vec4(a_texcoord, 0.0, 0.0);" in src
    assert "v_color = (a_color).x;" in src


def test_unsupported_inputs_name_their_declaration():
    loc = SourceLoc("s.frag", 3, 9)
    with pytest.raises(UnsupportedShaderError, match=r"s\.frag:3:9: .*v_foo.*hint: use one of"):
        vertex_source({"v_foo": "vec3"}, {"v_foo": loc})
    with pytest.raises(UnsupportedShaderError, match="ivec2"):
        vertex_source({"v_texcoord": "ivec2"}, {"v_texcoord": loc})


def test_mesh_defines():
    full = SimpleNamespace(normals=1, texcoords=1, colors=1, tangents=1)
    bare = SimpleNamespace(normals=1, texcoords=None, colors=None, tangents=None)
    assert mesh_defines(mesh_attributes(full)) == {
        "MODEL_VERTEX_COLOR": "1", "MODEL_VERTEX_NORMAL": "1", "MODEL_VERTEX_TANGENT": "1", "MODEL_VERTEX_TEXCOORD": "1"}
    assert mesh_defines(mesh_attributes(bare)) == {"MODEL_VERTEX_NORMAL": "1"}
    session = SimpleNamespace(objects=[SimpleNamespace(mesh=bare), SimpleNamespace(mesh=SimpleNamespace(
        normals=1, texcoords=1, colors=None, tangents=None))])
    assert session_attributes(session) == {"normal", "texcoord"}
    with pytest.raises(ValueError):
        mesh_defines(["uv"])
