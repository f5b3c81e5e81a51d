"""A profile's choice at one level, exactly as the profile made it: the one place that turns a
level (``e1`` … ``e4``) into its compiled variant and every option the cache runs with. (It sits
above the pipeline and the profile's data: the document, :mod:`rrcache.profiles`, compiles nothing.)

The profile's ``optimized/eN`` folders, ``rrcache instance PROFILE --level eN``,
``rrcache render PROFILE --level eN``, ``rrcache select --out`` and the report's "what to do
next" all go through here, so a level is reproduced with the profile's algorithm (a profile with
``--algorithm auto`` measures which is faster and keeps it), its refresh period, its refresh
block, pattern and depth tolerance, an adaptive choice's threshold and an amortized choice's
m, λ, history, filter and payload, never with a command's own defaults.

>>> from rrcache.selection import AdaptiveNode, CachedNode, Selection
>>> adaptive_kwargs(Selection((AdaptiveNode("n3", 40, 0.01, 8),)))
{'threshold': 0.01, 'fast_period': 8, 'spread': 0.0}
>>> adaptive_kwargs(Selection((CachedNode("n3", 40),)))
{}
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

from rrcache import kinds
from rrcache.errors import RRCacheError
from rrcache.selection import Selection


def level(prof, label: str) -> Selection:
    """The selection of ``prof`` labelled ``label`` (``e2``; case does not matter); an unknown
    level is an error naming the levels the profile has."""
    wanted = str(label).strip().lower()
    for sel in prof.selections:
        if (sel.label or "").lower() == wanted:
            return sel
    have = ", ".join(s.label for s in prof.selections if s.label) or "none"
    where = str(Path(prof.path) / "profile.json") if prof.path is not None else "profile.json"
    raise RRCacheError(f"no level {label!r} in this profile (its levels: {have})", where,
                       hint="give one of its levels, or 'rrcache select PROFILE --min-psnr DB' for another")


def algorithm_of(prof, sel: Selection) -> str:
    """The cache algorithm ``sel`` runs with: its own, else the profile's."""
    return sel.algorithm or prof.algorithm


def adaptive_kwargs(sel: Selection) -> dict:
    """The runtime's adaptive-refresh arguments of ``sel`` (empty unless its variant spec has a
    threshold: :func:`rrcache.kinds.spec_for`)."""
    if not sel.parts:
        return {}
    spec = kinds.spec_for(sel)
    if spec.threshold is None:
        return {}
    return {"threshold": float(spec.threshold), "fast_period": int(spec.fast_period), "spread": float(spec.spread)}


def runtime_options(prof, sel: Selection) -> dict:
    """Every run-time option of the cache for ``sel`` besides the period, as the keyword
    arguments of :class:`rrcache.runtime.CacheRuntime` (``block``, ``refresh``,
    ``depth_epsilon``, and an adaptive choice's ``threshold``, ``fast_period``, ``spread``)."""
    return dict(prof.settings.cache_options(), **adaptive_kwargs(sel))


def load_work(prof, include_dirs=()):
    """The profiled shader loaded again for the profile's session (its defines, include folders
    and vertex shader), checked to be the shader that was profiled; returns ``(work, session)``."""
    from rrcache.pipeline import load_for_session
    from rrcache.profiles.inputs import load_session_of

    # what profile.json names is the profiled shader and session, before anything parses them
    session = load_session_of(prof)
    work = load_for_session(prof.shader, session, prof.defines, list(include_dirs) + list(prof.include_dirs),
                            vertex=prof.vertex, term_scores=prof.term_scores)
    check_same_shader(prof, work)
    work.filter = prof.filter  # the variants compile as the profile trained them
    return work, session


def check_same_shader(prof, work) -> None:
    """Raise unless ``work`` (the shader loaded again for profile ``prof``) has the profiled hash;
    the error says which file changed, or that none did (never blames an edit that did not
    happen)."""
    from rrcache.glsl.frontend import describe_change

    if work.hash == prof.shader_hash:
        return
    what = describe_change(prof.shader_files or None, work.shader, prof.defines)
    vertex_hash = work.vertex.hash if work.vertex is not None else None
    if prof.vertex_hash is not None and vertex_hash != prof.vertex_hash:
        changed = f"the vertex shader '{work.vertex.path if work.vertex is not None else prof.vertex}' changed"
        what = changed if what.startswith("no shader file changed") else f"{what}; {changed}"
    if what.startswith("no shader file changed") or what.startswith("the record predates"):
        raise RRCacheError(f"the shader's hash differs from the profile's, though {what}" if what.startswith("no ")
                           else f"the shader's hash differs from the profile's: {what}",
                           str(prof.shader), hint="run 'rrcache profile' again to make a profile for it")
    raise RRCacheError(f"the shader changed since it was profiled: {what}", str(prof.shader),
                       hint="run 'rrcache profile' again, or restore the file")


def variant_of(prof, sel: Selection, work):
    """The compiled variant of ``sel`` with the profile's algorithm and the period it runs with
    (:func:`rrcache.pipeline.variant_for_selection`); the original shader has none (an error)."""
    from rrcache.pipeline import variant_for_selection

    return variant_for_selection(work, sel.replace(algorithm=algorithm_of(prof, sel)), **prof.settings.cache_options())


def original_note(prof, sel: Selection) -> str:
    """Why a level keeps the original shader, in words."""
    if prof.verdict is not None:
        return prof.verdict["answer"]
    return sel.fallback or "no cached variant is predicted to beat the original at this level"


def write(prof, sel: Selection, out_dir, work=None) -> list[str]:
    """Write the shader files of ``sel`` into ``out_dir``: every pass and ``manifest.json``
    (recording the period and every run-time option); for the original shader only a
    ``manifest.json`` saying so. ``work``: the profiled shader already loaded (else it is loaded
    again and must still have the profiled hash)."""
    from rrcache.atomic import OutputFolder

    if not isinstance(out_dir, OutputFolder):  # by rrcache.atomic's rule, into the chosen folder
        with OutputFolder(out_dir) as folder:
            return write(prof, sel, folder, work)
    if not sel.parts:
        return [out_dir.write_text("manifest.json", json.dumps(
            {"rrcache_selection": 1, "node": None, "shader": prof.shader, "note": original_note(prof, sel)},
            indent=2) + "\n")]
    if work is None:
        work, _session = load_work(prof)
    variant, period = variant_of(prof, sel, work)
    return variant.write(out_dir, period=period, runtime=runtime_options(prof, sel))


def describe_options(prof, sel: Selection) -> str:
    """The cache's options for ``sel`` in words: 'two-pass (the profile's choice: auto, from the
    ceiling: two-pass 1.60× against three-pass 1.30× ...), bilinear filter, refresh block 4,
    random refresh, depth tolerance 0.001' (how ``auto`` decided: :func:`algorithm_line`)."""
    from rrcache.profiles.document import algorithm_line

    algorithm = algorithm_of(prof, sel)
    how = algorithm_line(prof)[len(prof.algorithm):].strip()[1:-1]  # 'auto, from …' of 'two-pass (auto, from …)'
    if sel.algorithm and sel.algorithm != prof.algorithm:
        why = "this level's"
    else:
        why = f"the profile's choice: {how}" if how else "the profile's"
    opts = runtime_options(prof, sel)
    part = sel.parts[0] if sel.parts else None
    filter_ = getattr(part, "filter", None) or getattr(prof, "filter", None) or "bilinear"
    text = (f"{algorithm} ({why}), {filter_} filter, refresh block {opts['block']}, {opts['refresh']} refresh, "
            f"depth tolerance {opts['depth_epsilon']:g}")
    if "threshold" in opts:
        text += (f", adaptive refresh: threshold {opts['threshold']:g}, fast period {opts['fast_period']}, "
                 f"spread {opts['spread']:g}")
    return text
