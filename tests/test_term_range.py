"""The range of an estimator's terms (rrcache.analysis.term_range) and the range pragma
(``#pragma rrcache estimator range(LO, HI)``, rrcache.analysis.estimators)."""
from __future__ import annotations

import json
import math
import random
from pathlib import Path

import pytest
from click.testing import CliRunner

from rrcache.analysis.estimators import find_estimators, parse_pragma
from rrcache.errors import GLSLError, RRCacheError
from rrcache.glsl.frontend import parse_shader

ROOT = Path(__file__).resolve().parent.parent

HEAD = """#version 330
in vec2 v_texcoord;
uniform sampler2D u_tex;
uniform float u_gain;
out vec4 fragColor;
"""


def _shader(body: str, before: str = "float s = 0.0;", after: str = "fragColor = vec4(s);",
            globals_: str = "") -> str:
    return (HEAD + globals_ + "\nvoid main() {\n    " + before + "\n" + body + "\n    " + after + "\n}\n")


def _one(source: str, name: str = "t.frag"):
    table = find_estimators(parse_shader(source, name))
    assert len(table.estimators) == 1, [r.reason for r in table.rejected]
    return table.estimators[0]


def _range(body: str, **kw):
    e = _one(_shader(body, **kw))
    return e.term_range, e.range_source, e.range_reason


def _approx(r, lo, hi):
    return r is not None and math.isclose(r[0], lo, abs_tol=1e-12) and math.isclose(r[1], hi, abs_tol=1e-12)


# ----------------------------------------------------------------------------- the real scene

def test_pcf_shadow_taps_are_between_0_and_1():
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    work = load_for_session(str(ROOT / "shaders" / "pcf_shadows.glsl"), load_session(ROOT / "sessions" / "temple.json"))
    (e,) = find_estimators(work.shader).estimators
    assert e.id == "e1" and e.term_range == (0.0, 1.0) and e.range_source == "analysis"
    assert e.to_json()["term_range"] == [0.0, 1.0] and "range_reason" not in e.to_json()


def test_cli_nodes_json_shows_the_pcf_range():
    from rrcache.cli import cli

    out = CliRunner().invoke(cli, ["nodes", str(ROOT / "shaders" / "pcf_shadows.glsl"), "--json",
                                   "--session", str(ROOT / "sessions" / "temple.json")])
    assert out.exit_code == 0, out.output
    (e,) = json.loads(out.output)["estimators"]
    assert e["id"] == "e1" and e["term_range"] == [0.0, 1.0] and e["range_source"] == "analysis"


def _corpus_shaders():
    return sorted((ROOT / "shaders").glob("*.glsl")) + sorted((ROOT / "tests" / "corpus").glob("*.glsl"))


@pytest.mark.parametrize("path", _corpus_shaders(), ids=lambda p: p.name)
def test_every_corpus_estimator_has_a_range_or_a_reason(path):
    from rrcache.pipeline import load_for_session
    from rrcache.session import load_session

    if path.name == "pcf_shadows.glsl":
        session = load_session(ROOT / "sessions" / "temple.json")
    else:
        own = path.with_suffix(".json")
        session = load_session(own if own.exists() else ROOT / "tests" / "corpus" / "default_session.json")
    work = load_for_session(str(path), session)  # every shader here loads (none is skipped)
    for e in find_estimators(work.shader).estimators:
        assert (e.term_range is None) == (e.range_source is None)
        if e.term_range is None:
            assert e.range_reason.startswith("`"), e.range_reason
            assert "_rr_" not in e.range_reason  # the user's names, not the inliner's
        else:
            assert e.term_range[0] <= e.term_range[1] and e.range_source == "analysis"


# ----------------------------------------------------------------------------- the rules

def test_texture_reads_have_no_range_and_say_so():
    r, source, why = _range("    for (int i = 0; i < 8; i++) s += texture(u_tex, v_texcoord + float(i) * 0.01).r;")
    assert r is None and source is None
    assert "texture" in why and "`texture(u_tex, v_texcoord + float(i) * 0.01).r`" in why
    assert "format" in why


def test_a_texture_through_an_inlined_helper_names_the_users_expression():
    src = _shader("    for (int i = 0; i < 4; i++) s += tap(v_texcoord, float(i));",
                  globals_="float tap(vec2 uv, float k) { float t = texture(u_tex, uv * k).g; return t; }")
    e = _one(src)
    assert e.term_range is None and "`texture(u_tex, uv * k).g`" in e.range_reason
    assert e.to_json()["range_reason"] == e.range_reason and e.to_json()["term_range"] is None


def test_a_const_weighted_clamped_sum():
    r, source, _ = _range("    for (int i = 0; i < 8; i++) s += W * clamp(v_texcoord.x * float(i), 0.0, 1.0);",
                          globals_="const float W = 0.125;")
    assert _approx(r, 0.0, 0.125) and source == "analysis"
    # a const local, and a clamp whose value has no range at all
    r, _, _ = _range("    for (int i = 0; i < 8; i++) s += w * clamp(texture(u_tex, v_texcoord).r, -0.5, 1.0);",
                     before="float s = 0.0; const float w = 2.0;")
    assert _approx(r, -1.0, 2.0)


def test_subtracted_terms_are_negated():
    r, _, _ = _range("    for (int i = 0; i < 4; i++) s -= 2.0 * fract(v_texcoord.x * float(i));")
    assert _approx(r, -2.0, 0.0)
    r, _, _ = _range("    for (int i = 0; i < 4; i++) s = s - step(0.5, v_texcoord.x) * 0.5;")
    assert _approx(r, -0.5, 0.0)
    r, _, _ = _range("    for (int i = 0; i < 4; i++) s = smoothstep(0.0, 1.0, v_texcoord.y) + s;")
    assert _approx(r, 0.0, 1.0)


def test_a_uniform_has_no_range():
    r, source, why = _range("    for (int i = 0; i < 4; i++) s += u_gain * sin(float(i));")
    assert r is None and source is None and "`u_gain` is a uniform" in why


def test_values_from_before_the_loop_have_no_range():
    r, _, why = _range("    for (int i = 0; i < 4; i++) s += k * 0.5;", before="float s = 0.0; float k = 1.0;")
    assert r is None and "`k` is computed before the loop" in why
    r, _, why = _range("    for (int i = 0; i < 4; i++) s += v_texcoord.x;")
    assert r is None and "`v_texcoord` is a shader input" in why


def test_the_loop_index():
    r, _, _ = _range("    for (int i = 0; i < 8; i++) s += float(i) * 0.25;")
    assert _approx(r, 0.0, 1.75)
    r, _, _ = _range("    for (int i = 15; i >= 0; i -= 3) s += float(i);")  # 15, 12, ..., 0
    assert _approx(r, 0.0, 15.0)
    r, _, _ = _range("    for (int i = 1; i <= 4; i++) s += 1.0 / float(i);")
    assert _approx(r, 0.25, 1.0)
    r, _, _ = _range("    for (int i = 0; i < 32; i++) s += float(i / 16) + float(i - 16 * (i / 16)) * 0.0;")
    assert r is not None and r[0] <= 0.0 and r[1] >= 1.0 and r[1] <= 2.0


def test_locals_of_the_body_take_every_value_assigned_to_them():
    body = """    for (int i = 0; i < 4; i++) {
        float a = fract(v_texcoord.x * float(i));
        vec2 d = vec2(0.0);
        if (a > 0.5) { a = 2.0; d.y = -1.0; }
        s += a + d.y;
    }"""
    r, _, _ = _range(body)
    assert _approx(r, -1.0, 2.0)  # a in [0, 2], d.y in [-1, 0]


def test_updated_or_self_dependent_locals_have_no_range():
    r, _, why = _range("    for (int i = 0; i < 4; i++) { float a = 0.5; a += 0.25; s += a; }")
    assert r is None and "`a` has no known range" in why and "a += 0.25" in why
    r, _, why = _range("    for (int i = 0; i < 4; i++) { float a = 0.5; a = a * 0.5; s += a; }")
    assert r is None and "`a` is assigned a value computed from itself" in why
    r, _, why = _range("    for (int i = 0; i < 4; i++) { float a; float b = modf(v_texcoord.x, a); s += a; }")
    assert r is None and "modf" in why


def test_vectors_keep_one_hull_over_their_components():
    r, _, _ = _range("    for (int i = 0; i < 4; i++) acc += vec3(0.5, fract(v_texcoord.x), -1.0).zyx;",
                     before="vec3 acc = vec3(0.0);", after="fragColor = vec4(acc, 1.0);")
    assert _approx(r, -1.0, 1.0)
    r, _, _ = _range("    for (int i = 0; i < 3; i++) s += OFFS[i].y * 2.0;",
                     globals_="const vec2 OFFS[3] = vec2[3](vec2(0.1, -0.4), vec2(0.3, 0.2), vec2(-0.25, 0.0));")
    assert _approx(r, -0.8, 0.4)  # the .y of every element, times 2
    r, _, _ = _range("    for (int i = 0; i < 3; i++) s += TAPS[i].weight * sin(TAPS[i].offset.x);",
                     globals_="struct Tap { vec2 offset; float weight; };\n"
                              "const Tap TAPS[3] = Tap[3](Tap(vec2(-1.0, 3.0), 0.25), Tap(vec2(0.0), 0.5), "
                              "Tap(vec2(1.0, 0.0), 0.25));")
    assert _approx(r, -0.5, 0.5)
    r, _, _ = _range("    for (int i = 0; i < 3; i++) { vec2 o = OFFS[i]; s += o.x; }",
                     globals_="const vec2 OFFS[3] = vec2[3](vec2(0.1, -0.4), vec2(0.3, 0.2), vec2(-0.25, 0.0));")
    assert _approx(r, -0.4, 0.3)  # a local keeps one hull over its components


def test_several_accumulators_and_statements():
    # two accumulators: one hull over both
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { s += 0.5; w += sin(float(i)); }",
                     before="float s = 0.0; float w = 0.0;", after="fragColor = vec4(s, w, 0.0, 1.0);")
    assert _approx(r, -1.0, 1.0)
    # two additions to one accumulator in one iteration add up
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { s += 0.5; s += 0.25; }")
    assert _approx(r, 0.75, 0.75)
    # an inner loop of 3 adds three times
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { for (int j = 0; j < 3; j++) { s += 0.5 * float(j); } }")
    assert _approx(r, 0.0, 3.0)


def test_skipped_additions_add_zero():
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { if (v_texcoord.x > 0.5) s += 0.5; }")
    assert _approx(r, 0.0, 0.5)
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { if (v_texcoord.x > 0.5) continue; s += 1.0; s += 0.25; }")
    assert _approx(r, 0.0, 1.25)
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { v_texcoord.x > 0.5 ? (s += 2.0) : (s += 3.0); }")
    assert _approx(r, 0.0, 5.0)


def test_division_by_a_range_holding_zero_is_unknown():
    r, _, why = _range("    for (int i = 0; i < 4; i++) s += 1.0 / float(i);")
    assert r is None and "divides by `float(i)`" in why and "[0, 3]" in why


def test_built_in_rules():
    cases = {
        "mix(-1.0, 2.0, fract(v_texcoord.x))": (-1.0, 2.0),
        "mix(0.0, 1.0, float(i) * 0.5)": (0.0, 1.5),  # weight [0, 1.5]: a + t (b - a)
        "pow(fract(v_texcoord.x), 2.2)": (0.0, 1.0),
        "sqrt(fract(v_texcoord.x)) + abs(sin(v_texcoord.y))": (0.0, 2.0),
        "max(sin(v_texcoord.x), 0.0)": (0.0, 1.0),
        "min(cos(v_texcoord.x), -0.5)": (-1.0, -0.5),
        "exp(-float(i))": (math.exp(-3.0), 1.0),
        "dot(normalize(vec3(v_texcoord, 1.0)), vec3(0.5))": (-1.5, 1.5),
        "length(vec2(fract(v_texcoord.x), 0.0))": (0.0, math.sqrt(2.0)),
        "floor(float(i) * 0.5)": (0.0, 1.0),
        "mod(v_texcoord.x * 9.0, 0.25)": (0.0, 0.25),
        "float(v_texcoord.x > 0.5)": (0.0, 1.0),
    }
    for term, (lo, hi) in cases.items():
        r, _, why = _range(f"    for (int i = 0; i < 4; i++) s += {term};")
        assert _approx(r, lo, hi), (term, r, why)
    for term, word in {"dFdx(v_texcoord.x)": "dFdx", "pow(sin(v_texcoord.x), 2.0)": "pow",
                       "log(fract(v_texcoord.x))": "log", "mix(0.0, 1.0, v_texcoord.x)": "v_texcoord"}.items():
        r, _, why = _range(f"    for (int i = 0; i < 4; i++) s += {term};")
        assert r is None and word in why, (term, why)


def test_matrix_products_add_their_inner_products():
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { mat2 m = mat2(0.5, -0.5, 0.25, 1.0); acc += m * vec2(fract(v_texcoord.x)); }",
                     before="vec2 acc = vec2(0.0);", after="fragColor = vec4(acc, 0.0, 1.0);")
    # entries in [-0.5, 1], vector in [0, 1]: each component a sum of two products in [-0.5, 1]
    assert _approx(r, -1.0, 2.0)


# the interval rules against the functions they bound, on random inputs
_REFERENCE = {
    "abs": (1, abs), "sign": (1, lambda x: float((x > 0) - (x < 0))), "floor": (1, math.floor),
    "ceil": (1, math.ceil), "trunc": (1, math.trunc), "round": (1, lambda x: math.floor(x + 0.5)),
    "exp": (1, math.exp), "exp2": (1, lambda x: 2.0 ** x), "sinh": (1, math.sinh),
    "tanh": (1, math.tanh), "asinh": (1, math.asinh), "radians": (1, math.radians),
    "degrees": (1, math.degrees), "fract": (1, lambda x: x - math.floor(x)), "sin": (1, math.sin),
    "cos": (1, math.cos), "atan": (1, math.atan),
    "min": (2, min), "max": (2, max), "fma": (3, lambda a, b, c: a * b + c),
    "clamp": (3, lambda x, a, b: min(max(x, a), b)), "mix": (3, lambda a, b, t: a * (1 - t) + b * t),
    "step": (2, lambda e, x: 0.0 if x < e else 1.0), "+": (2, lambda a, b: a + b),
    "-": (2, lambda a, b: a - b), "*": (2, lambda a, b: a * b),
}
_POSITIVE = {"log": (1, math.log), "log2": (1, math.log2), "sqrt": (1, math.sqrt),
             "inversesqrt": (1, lambda x: 1 / math.sqrt(x)), "pow": (2, math.pow),
             "mod": (2, lambda x, y: x - y * math.floor(x / y)), "/": (2, lambda a, b: a / b)}


def test_interval_rules_bound_their_functions():
    rng = random.Random(7)
    for seed in range(4):
        loops, checks = [], []
        for name, (arity, f) in list(_REFERENCE.items()) + list(_POSITIVE.items()):
            positive = name in _POSITIVE
            ends = []
            for _ in range(arity):
                a, b = sorted(rng.uniform(0.01 if positive else -3.0, 3.0) for _ in range(2))
                ends.append((round(a, 3), round(b, 3) + 0.001))
            # mix(LO, HI, fract(...)) has exactly the range [LO, HI] for the analysis
            args = [f"mix({lo!r}, {hi!r}, fract(v_texcoord.x * {k + 1}.7))" for k, (lo, hi) in enumerate(ends)]
            term = f"({args[0]} {name} {args[1]})" if not name[0].isalpha() else f"{name}({', '.join(args)})"
            loops.append(f"    for (int i = 0; i < 2; i++) s += {term};")
            checks.append((name, f, ends))
        table = find_estimators(parse_shader(_shader("\n".join(loops)), f"r{seed}.frag"))
        assert len(table.estimators) == len(checks)
        for e, (name, f, ends) in zip(table.estimators, checks):
            assert e.term_range is not None, (name, e.range_reason)
            lo, hi = e.term_range
            for _ in range(200):
                xs = [rng.uniform(a, b) for a, b in ends]
                y = f(*xs)
                assert lo - 1e-9 <= y <= hi + 1e-9, (name, ends, xs, y, e.term_range)


# ----------------------------------------------------------------------------- the pragma

def test_a_declared_range_marks_the_loop_and_wins(tmp_path):
    src = _shader("    #pragma rrcache estimator range(-0.5, 2)\n"
                  "    for (int i = 0; i < 6; i++) { s += 0.1 * sin(float(i)) + 0.0 * s; }")
    e = _one(src)
    assert e.pragma and e.term_range == (-0.5, 2.0) and e.range_source == "pragma"
    # over a range the analysis proves, the declared one wins
    e = _one(_shader("    #pragma  rrcache estimator range( 0.0 , 4.0e0 )\n"
                     "    for (int i = 0; i < 6; i++) s += fract(v_texcoord.x);"))
    assert e.term_range == (0.0, 4.0) and e.range_source == "pragma"
    # the bare pragma works as before; the analysis still tries (this term reads the accumulator)
    e = _one(_shader("    #pragma rrcache estimator\n"
                     "    for (int i = 0; i < 6; i++) { s += 0.1 * sin(float(i)) + 0.0 * s; }"))
    assert e.pragma and e.term_range is None and "`s` is an accumulator" in e.range_reason


def test_cli_nodes_json_shows_a_declared_range(tmp_path):
    from rrcache.cli import cli

    path = tmp_path / "declared.frag"
    path.write_text(_shader("    #pragma rrcache estimator range(-1.0, 1.0)\n"
                            "    for (int i = 0; i < 8; i++) s += texture(u_tex, v_texcoord * float(i)).r;"))
    out = CliRunner().invoke(cli, ["nodes", str(path), "--json"])
    assert out.exit_code == 0, out.output
    (e,) = json.loads(out.output)["estimators"]
    assert e["pragma"] is True and e["term_range"] == [-1.0, 1.0] and e["range_source"] == "pragma"
    assert "range_reason" not in e


@pytest.mark.parametrize("args", ["range(1, 0)", "range(0.5, 0.5)", "range(a, b)", "range(0)",
                                  "range(0, 1) extra", "range(0, 1", "(0, 1)", "rang(0, 1)",
                                  "range(0, 1e999)", "range(0,,1)"])
def test_a_malformed_range_pragma_names_its_place(args):
    src = _shader(f"    #pragma rrcache estimator {args}\n"
                  "    for (int i = 0; i < 4; i++) s += 0.5;")
    line = src.splitlines().index(f"    #pragma rrcache estimator {args}") + 1
    with pytest.raises(GLSLError) as info:
        find_estimators(parse_shader(src, "bad.frag"))
    msg = str(info.value)
    assert msg.startswith(f"bad.frag:{line}:") and "malformed" in msg
    assert "range(LO, HI)" in msg  # the hint shows the syntax


def test_a_malformed_range_pragma_through_the_cli(tmp_path, capsys):
    from rrcache.cli import main

    path = tmp_path / "bad.frag"
    path.write_text(_shader("    #pragma rrcache estimator range(1.0, 0.0)\n"
                            "    for (int i = 0; i < 4; i++) s += 0.5;"))
    with pytest.raises(SystemExit) as info:
        main(["nodes", str(path), "--json"])
    err = capsys.readouterr().err
    assert info.value.code == 2 and "Traceback" not in err
    assert f"{path}:9:" in err and "must be below" in err and "range(LO, HI)" in err


def test_two_different_declared_ranges_for_one_loop_are_refused():
    src = _shader("    #pragma rrcache estimator range(0, 1)\n    #pragma rrcache estimator range(0, 2)\n"
                  "    for (int i = 0; i < 4; i++) s += 0.5;")
    with pytest.raises(GLSLError, match="two different ranges"):
        find_estimators(parse_shader(src, "two.frag"))
    # the error is at the pragma that differs from the first, not at a repeat of it
    src = _shader("    #pragma rrcache estimator range(0, 1)\n    #pragma rrcache estimator range(0, 1)\n"
                  "    #pragma rrcache estimator range(0, 2)\n    for (int i = 0; i < 4; i++) s += 0.5;")
    with pytest.raises(GLSLError) as err:
        find_estimators(parse_shader(src, "three.frag"))
    first = src.splitlines().index("    #pragma rrcache estimator range(0, 1)") + 1
    assert err.value.loc.line == first + 2 and f"at line {first})" in err.value.message


def test_a_bound_beyond_32_bit_floats_is_unknown():
    r, _, why = _range("    for (int i = 0; i < 4; i++) s += exp(float(i) * 30.0);")
    assert r is None and "32-bit" in why


def test_parse_pragma():
    assert parse_pragma("rrcache estimator") == (True, None)
    assert parse_pragma("rrcache estimator range(-1, +1.5f)") == (True, (-1.0, 1.5))
    assert parse_pragma("rrcache estimator range(- 2.5e-1, .5)") == (True, (-0.25, 0.5))
    assert parse_pragma("optimize(off)") is None and parse_pragma("STDGL invariant(all)") is None
    # our own pragmas misspelt are said, not ignored (the loop would silently lose its range)
    for bad in ("rrcache other", "rrcache estimators", "rrcache estimatorrange(0, 1)"):
        with pytest.raises(GLSLError, match="unknown '#pragma rrcache"):
            parse_pragma(bad)
    # a 32-bit float holds the ends
    with pytest.raises(GLSLError, match="32-bit"):
        parse_pragma("rrcache estimator range(0, 1e39)")


def test_integer_wrap_around_is_unknown():
    r, _, why = _range("    for (int i = 0; i < 4; i++) { uint u = uint(i); s += float(u - 1u); }")
    assert r is None and "`u - 1u` may wrap around" in why
    r, _, _ = _range("    for (int i = 0; i < 4; i++) { uint u = uint(i); s += float(u + 1u) + float(i % 3); }")
    assert _approx(r, 1.0, 6.0)


# random terms, evaluated in Python at every index, stay in the range the analysis gives them
def _random_term(rng: random.Random, depth: int, leaves: list):
    """``(glsl, f)``: a float expression and its value as a function of the environment."""
    def lit():
        c = round(rng.uniform(-3.0, 3.0), 2)
        return repr(c), lambda env: c

    if depth == 0 or rng.random() < 0.2:
        pick = rng.choice(leaves + ["lit", "lit"])
        if pick == "lit":
            return lit()
        if pick == "i":
            return "float(i)", lambda env: float(env["i"])
        return pick, lambda env: env[pick]
    sub = lambda: _random_term(rng, depth - 1, leaves)  # noqa: E731
    kind = rng.randrange(17)
    (a, fa), (b, fb), (c, fc) = sub(), sub(), sub()
    if kind == 0:
        return f"({a} + {b})", lambda env: fa(env) + fb(env)
    if kind == 1:
        return f"({a} - {b})", lambda env: fa(env) - fb(env)
    if kind == 2:
        return f"({a} * {b})", lambda env: fa(env) * fb(env)
    if kind == 3:
        k = rng.choice([-4.0, -0.5, 0.25, 2.0, 3.0])
        return f"({a} / {k!r})", lambda env: fa(env) / k
    if kind == 4:
        return f"fract({a})", lambda env: fa(env) - math.floor(fa(env))
    if kind == 5:
        return f"sin({a})", lambda env: math.sin(fa(env))
    if kind == 6:
        return f"abs({a})", lambda env: abs(fa(env))
    if kind == 7:
        lo, hi = sorted(round(rng.uniform(-2.0, 2.0), 2) for _ in range(2))
        return f"clamp({a}, {lo!r}, {hi!r})", lambda env: min(max(fa(env), lo), hi)
    if kind == 8:
        return (f"mix({a}, {b}, fract({c}))",
                lambda env: fa(env) * (1 - (fc(env) - math.floor(fc(env))))
                + fb(env) * (fc(env) - math.floor(fc(env))))
    if kind == 9:
        return f"min({a}, {b})", lambda env: min(fa(env), fb(env))
    if kind == 10:
        return f"max({a}, {b})", lambda env: max(fa(env), fb(env))
    if kind == 11:
        return f"({a} > {b} ? {c} : {a})", lambda env: fc(env) if fa(env) > fb(env) else fa(env)
    if kind == 12:
        return f"step({a}, {b})", lambda env: 0.0 if fb(env) < fa(env) else 1.0
    if kind == 13:
        return f"exp(clamp({a}, -3.0, 3.0))", lambda env: math.exp(min(max(fa(env), -3.0), 3.0))
    if kind == 14:
        k = rng.choice([0.5, 2.0, 3.3])
        return (f"pow(fract({a}), {k!r})", lambda env: math.pow(fa(env) - math.floor(fa(env)), k))
    if kind == 15:
        return f"floor({a})", lambda env: float(math.floor(fa(env)))
    return f"(-({a}))", lambda env: -fa(env)


def test_random_terms_stay_in_their_range():
    rng = random.Random(2026)
    known = 0
    for shader in range(8):
        loops, checks = [], []
        for k in range(25):
            (a1, f1), (a2, f2) = _random_term(rng, 2, ["i"]), _random_term(rng, 2, ["i"])
            term, ft = _random_term(rng, 3, ["i", "a"])
            cut = rng.randrange(6)
            sign = rng.choice(["+=", "-="])
            loops.append(f"    for (int i = 0; i < 6; i++) {{ float a = {a1}; if (i > {cut}) a = {a2}; "
                         f"s {sign} {term}; }}")

            def value(i, f1=f1, f2=f2, ft=ft, cut=cut, sign=sign):
                env = {"i": i}
                env["a"] = f2(env) if i > cut else f1(env)
                v = ft(env)
                return v if sign == "+=" else -v
            checks.append(value)
        table = find_estimators(parse_shader(_shader("\n".join(loops)), f"random{shader}.frag"))
        assert len(table.estimators) == len(checks)
        for e, value, text in zip(table.estimators, checks, loops):
            assert e.term_range is not None or e.range_reason, text
            if e.term_range is None:
                continue
            known += 1
            lo, hi = e.term_range
            for i in range(6):
                try:
                    v = value(i)
                except (ValueError, ZeroDivisionError, OverflowError):
                    continue
                tol = 1e-9 * max(1.0, abs(v))
                assert lo - tol <= v <= hi + tol, (text, i, v, e.term_range)
    assert known > 150  # the generator's terms mostly have a range
