"""The report tells what to do next: per level, what the files are, the code that runs them with
the level's options (executed here, unchanged, on the level's real files), the commands for
the same choice elsewhere and for another level; the summary gives the ceiling and every warning
of the run. Real demo profile (seconds), real GL."""
from __future__ import annotations

import html
import json
import re

import moderngl
import pytest

from rrcache.profiler import demo_profile
from rrcache.profiles.notices import run_warnings
from rrcache.report import REPORT_NAME
from rrcache.report.next_steps import PASS_ROLES, read_manifest, runtime_snippet


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo profile, shared with the report modules of one test run (made once, then loaded)."""
    return demo_profile(tmp_path_factory.getbasetemp() / "demo.rrprofile")


@pytest.fixture(scope="module")
def page(demo) -> str:
    return html.unescape(re.sub(r"<[^>]+>", " ", (demo.path / REPORT_NAME).read_text(encoding="utf-8")))


def test_each_level_says_what_its_files_are_and_how_to_get_them(demo, page):
    for sel in demo.selections:
        if not sel.parts:
            continue
        manifest = read_manifest(demo, sel)
        assert manifest is not None and manifest["algorithm"] == (sel.algorithm or demo.algorithm)
        for name, p in manifest["passes"].items():
            assert p["fragment"] in page and p["vertex"] in page
            assert PASS_ROLES[name.split("@")[0]][:40] in page
        for command in (f"rrcache instance {demo.path} --level {sel.label} --out DIR",
                        f"rrcache instance {demo.path} --level {sel.label} --target webgl2 --out DIR",
                        f"rrcache render {demo.path} --level {sel.label}"):
            assert command in page
    assert f"rrcache select {demo.path} --min-psnr" in page


def test_the_runtime_snippet_runs_the_levels_files(demo, gl_ctx, monkeypatch):
    """The report's code, as it is printed, makes the runtime from the level's files with the
    profile's options and runs frames (the draw callback is the user's: here it draws nothing)."""
    monkeypatch.setattr(moderngl, "create_standalone_context", lambda **kw: gl_ctx)  # the suite's one context
    ran = 0
    for sel in demo.selections:
        manifest = read_manifest(demo, sel)
        if manifest is None or not sel.parts:
            continue
        code = runtime_snippet(manifest, str(demo.path / sel.files), (64, 48)).replace("range(100)", "range(3)")
        scope: dict = {}
        exec(compile(code, f"<report snippet {sel.label}>", "exec"), scope)
        cache = scope["cache"]
        try:
            assert cache.algorithm == manifest["algorithm"] and cache.period == manifest["period"]
            assert cache.depth_epsilon == manifest["runtime"]["depth_epsilon"] and cache.clock == 3
            assert scope["image"].shape == (48, 64, 4)
        finally:
            cache.release()
            for program in scope["programs"].values():
                program.release()
        ran += 1
    assert ran >= 1


def test_summary_has_the_ceiling_and_every_warning(demo, page):
    ceiling = demo.measured_ceiling
    assert ceiling is not None and f"ceiling: {ceiling.summary()}" in page
    for warning in run_warnings(demo):
        assert f"warning: {warning}" in page
    # plain units: the covered pixels as a whole number, never 1.39730e+05
    assert f"{round(demo.pixels):,}" in page and not re.search(r"\d\.\d+e\+\d\d covered", page)


def test_run_warnings_are_kept_in_the_profile(tmp_path):
    """A warning raised while profiling is stored in profile.json (and shown by the report)."""
    import warnings

    from rrcache.profiler.demo import DEMO_SESSION, DEMO_SHADER, DEMO_SETTINGS
    from rrcache.profiler.run import profile
    from rrcache.profiles import TrainingSettings, load_profile

    # 6 training frames cannot reach the steady state of period 16: the settings warn
    settings = TrainingSettings(**dict(DEMO_SETTINGS, frames=6, budget_s=1.0, validate=False))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        prof = profile(DEMO_SHADER, DEMO_SESSION, tmp_path / "p", settings, plots=False)
    assert any("steady state" in str(w.message) for w in caught)  # raised for the caller too
    stored = json.loads((tmp_path / "p" / "profile.json").read_text())["warnings"]
    assert any("steady state" in w for w in stored) and load_profile(tmp_path / "p").warnings == prof.warnings
    assert any("steady state" in w for w in run_warnings(prof))
