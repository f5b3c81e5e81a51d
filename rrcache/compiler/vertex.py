"""The generated vertex shader and the mesh-attribute defines.

The harness draws every mesh with a vertex shader written here (``#version 330 core``) that
outputs the glslViewer varyings a fragment shader may read (docs/design.md §4), in world space:

=====================  ======  =========================================================
``v_position``         vec4    world position (``u_modelMatrix * position``)
``v_normal``           vec3    world normal (``normalize(u_normalMatrix * normal)``)
``v_texcoord``         vec2    texture coordinates (0 when the mesh has none)
``v_color``            vec4    vertex colour (opaque white when the mesh has none)
``v_tangent``          vec4    world tangent, w = handedness (0 when the mesh has none)
``v_objectPosition``   vec3    object-space position (solid textures on moving objects)
``v_lightCoord``       vec4    ``u_lightMatrix * v_position``: shadow-map coordinates (in
                               [0, 1] after the divide by w) when the light has a shadow map
``rr_prevClip``        vec4    clip position at the previous frame (reprojection cache)
=====================  ======  =========================================================

Only the varyings the fragment shader declares are written, converted to the declared size
(``in vec3 v_position`` gets ``.xyz``). Vertex attributes are ``a_position`` (vec3), ``a_normal``
(vec3), ``a_texcoord`` (vec2), ``a_color`` (vec4) and ``a_tangent`` (vec4).

>>> src = vertex_source({"v_normal": "vec3"})
>>> "out vec3 v_normal;" in src and "v_texcoord" not in src
True
>>> mesh_defines({"texcoord", "normal"})
{'MODEL_VERTEX_NORMAL': '1', 'MODEL_VERTEX_TEXCOORD': '1'}
"""
from __future__ import annotations

from typing import Iterable, Mapping, Optional

from rrcache.errors import SourceLoc, UnsupportedShaderError

# attribute -> (GLSL type, define set when the mesh has it)
ATTRIBUTES = {
    "position": ("vec3", None),
    "normal": ("vec3", "MODEL_VERTEX_NORMAL"),
    "texcoord": ("vec2", "MODEL_VERTEX_TEXCOORD"),
    "color": ("vec4", "MODEL_VERTEX_COLOR"),
    "tangent": ("vec4", "MODEL_VERTEX_TANGENT"),
}

# varying -> (natural size, value expression, attributes it reads, padding for a larger declaration)
VARYINGS = {
    "v_position": (4, "rr_world", ("position",), "1.0"),
    "v_normal": (3, "normalize(u_normalMatrix * a_normal)", ("normal",), "0.0"),
    "v_texcoord": (2, "a_texcoord", ("texcoord",), "0.0"),
    "v_color": (4, "a_color", ("color",), "1.0"),
    "v_tangent": (4, "vec4(normalize(mat3(u_modelMatrix) * a_tangent.xyz), a_tangent.w)", ("tangent",), "0.0"),
    "v_objectPosition": (3, "a_position", ("position",), "1.0"),
    "v_lightCoord": (4, "u_lightMatrix * rr_world", ("position",), "1.0"),
    "rr_prevClip": (4, "u_prevModelViewProjectionMatrix * vec4(a_position, 1.0)", ("position",), "1.0"),
}

# uniforms the vertex shader reads (set per object by the renderer)
VERTEX_UNIFORMS = ("u_modelMatrix", "u_modelViewProjectionMatrix", "u_normalMatrix", "u_prevModelViewProjectionMatrix",
                   "u_lightMatrix")

_FLOAT_TYPES = {"float": 1, "vec2": 2, "vec3": 3, "vec4": 4}


def mesh_attributes(mesh) -> frozenset[str]:
    """The optional attributes a ``MeshData`` carries (``normal texcoord color tangent``).

    >>> from types import SimpleNamespace
    >>> sorted(mesh_attributes(SimpleNamespace(normals=[0], texcoords=None, colors=[1], tangents=None)))
    ['color', 'normal']
    """
    present = set()
    for attr, field in (("normal", "normals"), ("texcoord", "texcoords"), ("color", "colors"), ("tangent", "tangents")):
        if getattr(mesh, field, None) is not None:
            present.add(attr)
    return frozenset(present)


def session_attributes(session) -> frozenset[str]:
    """The union of the optional attributes of every object's mesh in a session."""
    found: set[str] = set()
    for obj in session.objects:
        found |= mesh_attributes(obj.mesh)
    return frozenset(found)


def mesh_defines(attributes: Iterable[str]) -> dict[str, str]:
    """The ``MODEL_VERTEX_*`` defines (value ``"1"``) for a set of mesh attributes, sorted by name.

    >>> mesh_defines(["color"])
    {'MODEL_VERTEX_COLOR': '1'}
    """
    names = []
    for attr in attributes:
        if attr not in ATTRIBUTES:
            raise ValueError(f"unknown mesh attribute {attr!r}; expected one of {', '.join(ATTRIBUTES)}")
        define = ATTRIBUTES[attr][1]
        if define:
            names.append(define)
    return {name: "1" for name in sorted(names)}


def shadow_defines(session) -> dict[str, str]:
    """``LIGHT_SHADOWMAP`` and ``LIGHT_SHADOWMAP_SIZE`` (glslViewer's) when the session's light has
    a shadow map, else nothing.

    >>> from types import SimpleNamespace
    >>> shadow_defines(SimpleNamespace(shadow_map=SimpleNamespace(size=512)))
    {'LIGHT_SHADOWMAP': 'u_lightShadowMap', 'LIGHT_SHADOWMAP_SIZE': '512.0'}
    """
    shadow = getattr(session, "shadow_map", None)
    if shadow is None:
        return {}
    return {"LIGHT_SHADOWMAP": "u_lightShadowMap", "LIGHT_SHADOWMAP_SIZE": f"{float(shadow.size)!r}"}


def session_defines(session) -> dict[str, str]:
    """Every define a session implies: the meshes' ``MODEL_VERTEX_*`` and the light's
    ``LIGHT_SHADOWMAP*``."""
    return {**mesh_defines(session_attributes(session)), **shadow_defines(session)}


def _convert(expr: str, size: int, pad: str, declared: int) -> str:
    if declared == size:
        return expr
    if declared < size:
        return f"({expr}).{'xyzw'[:declared]}"
    fill = ", ".join(["0.0"] * (declared - size - 1) + [pad])
    return f"vec{declared}({expr}, {fill})"


def vertex_for(inputs: Mapping[str, str], locs: Optional[Mapping[str, Optional[SourceLoc]]] = None,
               user=None, prev_clip: bool = False, invariant: Optional[bool] = None) -> str:
    """The vertex shader of a program whose fragment shader reads ``inputs``: the user's own
    (a :class:`rrcache.compiler.user_vertex.UserVertex`, checked against ``inputs``) when given,
    else the generated one; ``prev_clip`` adds ``rr_prevClip`` and ``invariant gl_Position`` (the
    cached variants' passes); ``invariant`` adds ``invariant gl_Position`` whatever ``prev_clip``
    (every pass of a variant needs it: the depth tests between passes compare exact depths).

    >>> "out vec2 v_texcoord;" in vertex_for({"v_texcoord": "vec2"})
    True
    """
    if user is not None:
        user.check_inputs(inputs, locs)
        return user.source(prev_clip=prev_clip)
    wanted = dict(inputs)
    if prev_clip:
        wanted["rr_prevClip"] = "vec4"
    text = vertex_source(wanted, locs)
    if not (prev_clip if invariant is None else invariant):
        return text
    first, _, rest = text.partition("\n")
    return f"{first}\ninvariant gl_Position;\n{rest}"


def vertex_source(inputs: Mapping[str, str], locs: Optional[Mapping[str, Optional[SourceLoc]]] = None) -> str:
    """The vertex shader text writing the fragment inputs ``inputs`` (name → declared GLSL type).

    Raises :class:`UnsupportedShaderError` (at the declaration when ``locs`` knows it) for an input
    the harness cannot supply or a type it cannot convert to.

    >>> print(vertex_source({"v_texcoord": "vec2"}).splitlines()[0])
    #version 330 core
    """
    locs = locs or {}
    attrs = {"position"}
    outs = []
    for name, declared in sorted(inputs.items()):
        if name not in VARYINGS:
            raise UnsupportedShaderError(
                f"fragment input `{name}` is not a varying the harness supplies",
                locs.get(name),
                hint=f"use one of {', '.join(v for v in VARYINGS if not v.startswith('rr_'))} "
                     "(docs/design.md §4), or give the vertex shader that writes it (--vert FILE, or "
                     "\"vertex\" in the session)",
            )
        if declared not in _FLOAT_TYPES:
            raise UnsupportedShaderError(
                f"fragment input `{name}` is declared `{declared}`; the harness supplies it as a float vector",
                locs.get(name),
                hint=f"declare it as vec{VARYINGS[name][0]}",
            )
        size, expr, reads, pad = VARYINGS[name]
        attrs.update(reads)
        outs.append((name, declared, _convert(expr, size, pad, _FLOAT_TYPES[declared])))
    lines = ["#version 330 core"]
    lines += [f"in {ATTRIBUTES[a][0]} a_{a};" for a in ATTRIBUTES if a in attrs]
    lines += ["uniform mat4 u_modelMatrix;", "uniform mat4 u_modelViewProjectionMatrix;"]
    if "normal" in attrs:
        lines.append("uniform mat3 u_normalMatrix;")
    if "rr_prevClip" in inputs:
        lines.append("uniform mat4 u_prevModelViewProjectionMatrix;")
    if "v_lightCoord" in inputs:
        lines.append("uniform mat4 u_lightMatrix;")
    lines += [f"out {declared} {name};" for name, declared, _ in outs]
    lines += ["void main() {", "    vec4 rr_world = u_modelMatrix * vec4(a_position, 1.0);"]
    lines += [f"    {name} = {value};" for name, _, value in outs]
    lines += ["    gl_Position = u_modelViewProjectionMatrix * vec4(a_position, 1.0);", "}", ""]
    return "\n".join(lines)
