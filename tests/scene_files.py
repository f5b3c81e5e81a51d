"""The scene and shader scaffolding the rendering and profiling tests share (not a test module).

- :data:`PROLOGUE`: what the harness feeds a glslViewer-style fragment shader (positions,
  normals, object-space positions, the light) and ``u_scale``; :func:`fragment` puts a shader
  together from it; :data:`WAVE` the smooth noise several test shaders sum.
- :func:`session_doc`: a session document around an icosphere (64×48, 12 frames, a camera
  moving a little, an orbiting light unless told otherwise); :data:`SPHERE`,
  :data:`STATIC_CAMERA`, :data:`FIXED_LIGHT`.
- :func:`write_scene`: a shader and its session written into a test's folder.
- :func:`node_named`: a shader loaded for a session, its node table, the harness's prepared
  source and the node whose text is given.
- The profile of the tests: :data:`SHADER` (three octaves of wave noise, lit), :data:`SESSION`,
  the training :data:`SETTINGS` and their command-line form :data:`CLI_SETTINGS`.
"""
from __future__ import annotations

import json

PROLOGUE = """#version 330
in vec4 v_position;
in vec3 v_normal;
in vec3 v_objectPosition;
uniform vec3 u_light;
uniform float u_scale;
"""

WAVE = """float wave(vec3 p, float f) {
    return sin(p.x * f + 1.3 * cos(p.y * f)) * cos(p.z * f * 0.7 + sin(p.x * f * 1.9));
}
"""


def fragment(main: str, helpers: str = "", uniforms: tuple[str, ...] = ()) -> str:
    """A fragment shader: :data:`PROLOGUE`, more ``uniforms`` (``"float u_gain"``), the output
    ``fragColor``, the ``helpers`` and ``main`` (each separated by a blank line)."""
    head = PROLOGUE + "".join(f"uniform {u};\n" for u in uniforms) + "out vec4 fragColor;\n"
    return "\n".join(part for part in (head, helpers, main) if part)


SPHERE = {"procedural": {"type": "icosphere", "radius": 1.0, "subdivisions": 3}}
STATIC_CAMERA = [{"frame": 0, "eye": [0, 0.5, 3.2], "target": [0, 0, 0], "up": [0, 1, 0]}]
ORBIT_LIGHT = {"color": [1, 1, 1], "orbit": {"center": [0, 0, 0], "radius": 4, "height": 3,
                                             "degrees_per_frame": 3}}
FIXED_LIGHT = {"color": [1, 1, 1], "keyframes": [{"frame": 0, "position": [3, 3, 3]}]}


def moving_camera(frames: int, start=(0, 0.5, 3.2), end=(1.2, 0.6, 2.9)) -> list:
    """Two camera keyframes looking at the origin, from ``start`` at frame 0 to ``end`` at the
    last frame."""
    return [{"frame": 0, "eye": list(start), "target": [0, 0, 0], "up": [0, 1, 0]},
            {"frame": frames - 1, "eye": list(end), "target": [0, 0, 0], "up": [0, 1, 0]}]


def session_doc(resolution=(64, 48), frames: int = 12, camera=None, light=None, objects=None,
                uniforms=None, near: float = 0.1, far: float = 50.0) -> dict:
    """A session document (the ``rrcache_session`` JSON): by default :func:`moving_camera`,
    :data:`ORBIT_LIGHT`, one :data:`SPHERE` and ``u_scale`` 3."""
    return {
        "rrcache_session": 1, "resolution": list(resolution), "frames": frames, "fps": 30,
        "camera": {"fov": 45, "near": near, "far": far,
                   "keyframes": camera if camera is not None else moving_camera(frames)},
        "light": light if light is not None else ORBIT_LIGHT,
        "objects": objects if objects is not None else [SPHERE],
        "uniforms": uniforms if uniforms is not None else {"u_scale": 3.0},
    }


def write_scene(folder, shader: str = None, session: dict = None, shader_name: str = "noise.frag",
                session_name: str = "orbit.json"):
    """Write ``shader`` (default :data:`SHADER`) and ``session`` (default :data:`SESSION`) into
    ``folder`` (made if missing); returns their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    shader_path, session_path = folder / shader_name, folder / session_name
    shader_path.write_text(SHADER if shader is None else shader)
    session_path.write_text(json.dumps(SESSION if session is None else session))
    return shader_path, session_path


def node_named(shader_path, session, text: str):
    """``(table, prepared, node)``: the node table of ``shader_path`` loaded for ``session`` (a
    loaded :class:`Session`), the harness's prepared source, and the node (listed or left out)
    whose text is ``text``."""
    from rrcache.analysis import cacheable_nodes
    from rrcache.glsl.frontend import load_shader
    from rrcache.compiler.prepared import prepare_file
    from rrcache.compiler.vertex import mesh_defines, session_attributes

    shader = load_shader(shader_path, defines=mesh_defines(session_attributes(session)))
    prepared = prepare_file(shader_path, session)
    table = cacheable_nodes(shader)
    node = next(n for n in list(table.nodes) + list(table.excluded) if n.text == text)
    return table, prepared, node


# ----------------------------------------------------------------------------- the tests' profile

SHADER = fragment("""void main() {
    vec3 p = v_objectPosition * u_scale;
    float n = 0.5 + 0.25 * wave(p, 1.0) + 0.125 * wave(p, 2.1) + 0.0625 * wave(p, 4.3);
    vec3 albedo = mix(vec3(0.9, 0.8, 0.6), vec3(0.3, 0.2, 0.1), n);
    vec3 nrm = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    float diffuse = max(dot(nrm, l), 0.0);
    fragColor = vec4(albedo * (0.2 + 0.8 * diffuse), 1.0);
}
""", WAVE)

SESSION = session_doc()

#: the settings of every test profile: training at 32×24, six timing frames; nothing cached beats
#: the original on this tiny scene, so the ceiling must not stop the training (min_gain 0)
SETTINGS = dict(periods=(2, 4, 8), resolution=(32, 24), timing_frames=6, timing_periods=(2, 8), min_gain=0.0)
CLI_SETTINGS = ["--periods", "2,4,8", "--resolution", "32x24", "--timing-frames", "6", "--timing-periods", "2,8",
                "--min-gain", "0"]
