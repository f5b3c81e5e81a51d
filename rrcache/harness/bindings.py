"""Which value feeds each active uniform of a program: built-in, session uniform or session texture.

:func:`plan_bindings` checks the shader against the session once, before any frame is drawn:

- a uniform or sampler the program uses that neither the harness (docs/design.md §4 built-ins) nor
  the session supplies is an error naming the declaration (``shader.frag:line:col``) and the
  session file, saying what to add;
- a session uniform or texture the shader does not declare is a *note*, never an error (sessions
  are shared between shaders).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import moderngl

from rrcache.errors import SessionError, UnsupportedShaderError
from rrcache.gl.uniforms import encode_uniform, opaque_type_name, sampler_kind
from rrcache.compiler.prepared import PreparedShader

# uniforms the harness sets itself (per frame or per object); name -> expected GLSL type
BUILTINS = {
    "u_camera": "vec3", "u_light": "vec3", "u_lightColor": "vec3", "u_resolution": "vec2",
    "u_time": "float", "u_frame": "int", "u_modelMatrix": "mat4", "u_viewMatrix": "mat4",
    "u_projectionMatrix": "mat4", "u_modelViewProjectionMatrix": "mat4", "u_normalMatrix": "mat3",
    "u_prevModelViewProjectionMatrix": "mat4", "u_reprojectionMatrix": "mat4", "u_lightMatrix": "mat4",
}

#: the sampler of the light's shadow map (a depth texture, sampled ``texture(...).r``)
SHADOW_SAMPLER = "u_lightShadowMap"
#: what only a light with a shadow map supplies
SHADOW_NAMES = (SHADOW_SAMPLER, "u_lightMatrix")

_PATH = re.compile(r"([A-Za-z_]\w*)|\[(\d+)\]")


def base_name(active_name: str) -> str:
    """The declared name of an active uniform (``lights[2].color`` → ``lights``)."""
    return _PATH.match(active_name).group(1)


def lookup(values: dict, active_name: str):
    """The value for an active uniform name inside the session values (struct members are dict
    keys, array elements list items); raises ``KeyError`` when a part is missing."""
    parts = _PATH.findall(active_name)
    value = values[parts[0][0]]
    for ident, index in parts[1:]:
        if ident:
            if not isinstance(value, dict):
                raise KeyError(ident)
            value = value[ident]
        else:
            try:
                value = value[int(index)]
            except (IndexError, TypeError):
                raise KeyError(index) from None
    return value


@dataclass
class BindingPlan:
    """Active uniforms by source: ``builtins`` (name → Uniform), ``session`` ([(active name,
    Uniform)]), ``samplers`` ([(name, Uniform, kind)]), and the ``notes`` for the user."""

    builtins: dict = field(default_factory=dict)
    session: list = field(default_factory=list)
    samplers: list = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    shadow: object = None  # the u_lightShadowMap uniform when the program samples the shadow map


def _example(uniform) -> str:
    kind = uniform.fmt[-1]
    zero = "0" if kind in "iI" else "0.0"
    n = uniform.dimension * uniform.array_length
    return zero if n == 1 else "[" + ", ".join([zero] * n) + "]"


def active_uniforms(program: moderngl.Program) -> dict[str, moderngl.Uniform]:
    """The program's active uniforms by their (driver) name."""
    return {name: program[name] for name in program if isinstance(program[name], moderngl.Uniform)}


def plan_bindings(program: moderngl.Program, prepared: PreparedShader, session,
                  runtime_prefix: str = "rr_") -> BindingPlan:
    """Sort the program's active uniforms by source and check the session supplies the rest.

    Uniforms whose name starts with ``runtime_prefix`` belong to the reprojection cache
    (:mod:`rrcache.runtime` binds them) and are left out of the plan.

    Raises :class:`SessionError` for a uniform or sampler with no value, a value of the wrong
    shape or a texture of the wrong kind; :class:`UnsupportedShaderError` for a sampler type the
    harness does not bind or a built-in declared with another type.
    """
    plan = BindingPlan()
    values = session.uniform_values(0)
    textures = getattr(session, "textures", {}) or {}
    session_path = str(session.path)
    active = active_uniforms(program)
    for name, uniform in sorted(active.items()):
        if runtime_prefix and name.startswith(runtime_prefix):
            continue
        base = base_name(name)
        where = prepared.where(base)
        decl = prepared.declaration(base)
        loc = decl.loc if decl is not None else None
        if base in SHADOW_NAMES and getattr(session, "shadow_map", None) is None:
            raise SessionError(
                f"the shader uses `{base}` (declared at {where}) but the session's light has no shadow map",
                session_path, "light", hint='add "shadow_map": {"size": 1024} to "light"')
        kind = sampler_kind(uniform)
        if kind is not None and base == SHADOW_SAMPLER:
            if opaque_type_name(uniform) != "sampler2D" or uniform.array_length != 1:
                raise UnsupportedShaderError(f"`{base}` must be declared sampler2D", loc,
                                             hint="glslViewer's shadow map is a sampler2D depth texture")
            plan.shadow = uniform
            continue
        if kind is not None:
            type_name = opaque_type_name(uniform)
            if kind == "other" or type_name[0] in "iu" or uniform.array_length != 1:
                raise UnsupportedShaderError(
                    f"sampler `{name}` of type {type_name}{'[]' if uniform.array_length != 1 else ''} is not supported",
                    loc, hint="the harness binds single float sampler2D and samplerCube uniforms")
            asset = textures.get(base)
            if asset is None:
                raise SessionError(
                    f"the shader samples `{base}` ({type_name}, declared at {where}) but the session has no such texture",
                    session_path, "textures",
                    hint=f'add "{base}": "path/to/image.exr" to "textures"')
            if getattr(asset, "kind", "2d") != kind:
                raise SessionError(
                    f"texture `{base}` is a {getattr(asset, 'kind', '2d')} image but the shader declares it "
                    f"{type_name} at {where}", session_path, f"textures.{base}",
                    hint="give a cube map (six faces) for samplerCube, a single image for sampler2D")
            plan.samplers.append((base, uniform, kind))
            continue
        if base in BUILTINS:
            plan.builtins[name] = uniform
            continue
        try:
            value = lookup(values, name)
        except KeyError:
            raise SessionError(
                f"the shader uses uniform `{name}` (declared at {where}) but the session gives it no value",
                session_path, "uniforms",
                hint=f'add "{base}": {_example(uniform) if name == base else "..."} to "uniforms"') from None
        try:
            encode_uniform(uniform, value)
        except ValueError as err:
            raise SessionError(f"value of uniform `{name}` (declared at {where}) does not fit: {err}",
                               session_path, f"uniforms.{base}") from None
        plan.session.append((name, uniform))
    shader_name = prepared.path
    for name in sorted(values):
        if name in BUILTINS:
            plan.notes.append(f"session uniform `{name}` is a built-in the harness sets itself; the session value is ignored")
        elif name not in prepared.uniforms and not any(base_name(a) == name for a in active):
            plan.notes.append(f"session uniform `{name}` is not declared by {shader_name}; ignored")
    for name in sorted(textures):
        if name not in prepared.uniforms and name not in active:
            plan.notes.append(f"session texture `{name}` is not declared by {shader_name}; ignored")
    return plan

