"""Shared test fixtures.

``gl_ctx`` is the process-wide GL context (made by ``rrcache.gl.context.get_context``, the only
place a context is created). Every test that uses it is checked afterwards for a clean GL error
state (``ctx.error == "GL_NO_ERROR"``), the way moderngl's own tests do. llvmpipe runs with one
thread (``LP_NUM_THREADS=1``): the test machines are small and shared.
"""
from __future__ import annotations

import os

import pytest

# the table of extreme cases and bad input (--stability-table PATH; the stability_case fixture)
from stability_table import (pytest_addoption, pytest_configure, pytest_runtest_makereport,  # noqa: F401
                             pytest_sessionfinish, stability_case)

os.environ.setdefault("LP_NUM_THREADS", "1")


@pytest.fixture(scope="session")
def gl_ctx():
    """The shared moderngl context (EGL, GL >= 3.3 core)."""
    from rrcache.gl.context import get_context

    return get_context()


@pytest.fixture(autouse=True)
def _gl_error_state(request):
    """After a test that used ``gl_ctx``: the GL error flag must be clear."""
    uses_gl = "gl_ctx" in request.fixturenames
    if uses_gl:
        ctx = request.getfixturevalue("gl_ctx")
        before = ctx.error
        assert before == "GL_NO_ERROR", f"GL error left by an earlier test: {before}"
    yield
    if uses_gl:
        after = request.getfixturevalue("gl_ctx").error
        assert after == "GL_NO_ERROR", f"the test left a GL error: {after}"
