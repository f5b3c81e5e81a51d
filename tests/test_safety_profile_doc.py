"""``profile.json`` damaged or edited (issue 16), against the profile document's validator
(:mod:`rrcache.profiles.document`): NaN, infinite, negative and null α, λ, t_hit, t_miss (as the
node's fields and in the fitted models the selection computes with), wrong types, JSON nested
100,000 deep. Each is refused on load with the key path; through ``rrcache select`` it is one
line and exit 2. The document is a real one, written by a real ``rrcache profile`` run."""
from __future__ import annotations

import json
import shutil

import pytest

from rrcache.errors import RRCacheError
from rrcache.profiles.document import load_profile
from safety_cli import made_profile, one_error_line, rrcache  # noqa: F401 (a fixture)

AREA = "safety: profile.json damaged or edited"


@pytest.fixture(scope="module")
def profiled(made_profile):
    return made_profile / "p"


def _trained(doc) -> int:
    return next(i for i, n in enumerate(doc["nodes"]) if n["trained"])


# name: (the key of the first trained node (or of the document), the value put there, what the message names)
CASES = {
    "alpha NaN": ("alpha", "NaN", "NaN is not a JSON number"),
    "alpha infinite (1e999)": ("alpha", 1e999, "nodes[T].alpha"),
    "alpha negative": ("alpha", -0.5, "nodes[T].alpha"),
    "alpha null on a trained node": ("alpha", None, "nodes[T].alpha"),
    "lambda negative": ("lam", -1.0, "nodes[T].lam"),
    "lambda null": ("lam", None, "nodes[T].lam"),
    "t_hit infinite": ("t_hit", 1e999, "nodes[T].t_hit"),
    "t_miss negative": ("t_miss", -1e-5, "nodes[T].t_miss"),
    "t_miss null": ("t_miss", None, "nodes[T].t_miss"),
    "fitted alpha infinite (error_fit)": (("error_fit", "alpha"), 1e999, "nodes[T].error_fit.alpha"),
    "fitted t_miss negative (perf_fit)": (("perf_fit", "t_miss"), -3.0, "nodes[T].perf_fit.t_miss"),
    "fitted t_hit null (perf_fit)": (("perf_fit", "t_hit"), None, "nodes[T].perf_fit.t_hit"),
    "hit rate of 7": (("hit_rates", 0), 7.0, "nodes[T].hit_rates[0]"),
    "mu a string": ("mu", "high", "mu"),
    "nodes an object": ("nodes", {}, "nodes"),
    "alpha a list": ("alpha", [1, 2], "nodes[T].alpha"),
}


def _edit(doc, name):
    key, value, _ = CASES[name]
    if key in ("mu", "nodes"):
        doc[key] = value
        return
    node = doc["nodes"][_trained(doc)]
    if isinstance(key, tuple):
        node[key[0]][key[1]] = value
    else:
        node[key] = value


@pytest.mark.parametrize("name", list(CASES), ids=lambda n: n.replace(" ", "-"))
def test_bad_profile_json_is_refused_with_the_key_path(profiled, tmp_path, stability_case, name):
    folder = tmp_path / "p"
    shutil.copytree(profiled, folder)
    doc = json.loads((folder / "profile.json").read_text())
    t = _trained(doc)
    key, value, expected = CASES[name]
    if value == "NaN":  # json.dumps would write NaN itself, but say so plainly
        doc["nodes"][t]["alpha"] = "__NAN__"
        text = json.dumps(doc).replace('"__NAN__"', "NaN")
    else:
        _edit(doc, name)
        # an infinity as a user's editor writes it: 1e999 (json.dumps would write Infinity)
        text = json.dumps(doc).replace("Infinity", "1e999")
    (folder / "profile.json").write_text(text)
    expected = expected.replace("[T]", f"[{t}]")
    given = (f"nodes[{t}].alpha = NaN (the JSON token)" if value == "NaN"
             else f"{expected.split(':')[0]} = {value!r}")
    case = stability_case(f"profile.json: {name}", AREA, f"{given} in a real profile")
    with pytest.raises(RRCacheError) as info:
        load_profile(folder)
    msg = str(info.value)
    case.observe(error=msg.replace(str(folder), "P"))
    assert expected in msg and "profile.json" in msg


def test_deep_json_and_cli_one_line(profiled, tmp_path, stability_case):
    folder = tmp_path / "p"
    shutil.copytree(profiled, folder)
    doc = json.loads((folder / "profile.json").read_text())
    doc["plan"] = "__DEEP__"
    (folder / "profile.json").write_text(json.dumps(doc).replace('"__DEEP__"', "[" * 100_000 + "]" * 100_000))
    case = stability_case("profile.json: JSON nested 100,000 deep", AREA,
                          "'plan' replaced by 100,000 nested lists; load_profile and rrcache select")
    with pytest.raises(RRCacheError, match="nested too deeply"):
        load_profile(folder)
    code, _, lines = rrcache(tmp_path, "select", "p", "--max-error", "0.01")
    line = one_error_line(code, lines)
    # and a wrong type through the CLI
    doc["plan"] = None
    doc["mu"] = "high"
    (folder / "profile.json").write_text(json.dumps(doc))
    code2, _, lines2 = rrcache(tmp_path, "select", "p", "--max-error", "0.01")
    line2 = one_error_line(code2, lines2)
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP"), wrong_type=line2.replace(str(tmp_path), "TMP"))
    assert "nested too deeply" in line and "profile.json" in line
    assert "profile.json: mu: must be a finite number" in line2


def test_the_real_profile_loads(profiled):
    prof = load_profile(profiled)
    assert prof.trained_nodes and prof.select(1.0) is not None
