"""The short training pass that orders the terms of a sum whose weights the analysis cannot fold.

:mod:`rrcache.analysis.sums` puts the terms of a sum the unroller separated in the order that
makes its partial sums good to cache: static terms first, then the lightest where the weights
fold to constants. Where they do not (a loop over lights whose contribution depends on the
surface), :func:`measure_terms` measures, for each term, what caching it alone costs in error:
the term's node is cached at ``period`` beside the original over a few frames at a small size,
and the mean RGB L2 error of the result is its score. That one number holds both what the issue
asks for, the term's contribution to the colour and how much it changes between frames (a term
that is large but still, or changing but small, scores low). Lower scores go first, so a prefix
holds the terms it costs least to keep.

The scores are keyed by :func:`rrcache.analysis.sums.chain_key` and the terms' labels, and passed
back to the analysis (``load_for_session(..., term_scores=)``); node ids then refer to the
reordered program, so whatever uses them later must be given the same scores.
"""
from __future__ import annotations

from typing import Optional, Sequence

from rrcache.analysis.sums import chain_key, chains_to_measure, term_values

#: what the pass measures, by default: a few frames at a small size, the term cached this long
DEFAULT_FRAMES = 6
DEFAULT_SIZE = (64, 48)
DEFAULT_PERIOD = 8


def measure_terms(work, session, frames: Optional[Sequence[int]] = None, resolution=DEFAULT_SIZE,
                  period: int = DEFAULT_PERIOD, moving: Sequence[str] = (), progress=None) -> dict:
    """``{chain_key: {term label: score}}`` for every run of ``work``'s analysed program that
    :func:`rrcache.analysis.sums.chains_to_measure` lists (runs whose terms are not all listed
    nodes are left out). ``frames``: the session frames (default the first
    :data:`DEFAULT_FRAMES`); ``moving``: the session's per-frame inputs the analysis used."""
    from rrcache.harness.cached import CachedRenderer
    from rrcache.harness.metrics import mean_l2
    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import variant_for

    frames = list(frames if frames is not None else range(min(DEFAULT_FRAMES, session.frames)))
    listed = {id(n.node): n.id for n in work.table.nodes}
    todo = []
    for chain in chains_to_measure(work.table.shader.unit, moving):
        for accumulator, kind in chain.accumulators.items():
            if kind != "+":
                continue
            values = term_values(chain, accumulator)
            ids = {label: listed.get(id(expr)) for label, expr in values.items()}
            if len(ids) == len(chain.terms) and all(ids.values()):
                todo.append((chain_key(chain), ids))
                break
    if not todo:
        return {}
    out: dict = {}
    with Renderer(work.prepared, session, resolution) as original:
        reference = [original.render_frame(i) for i in frames]
    total, done = sum(len(ids) for _key, ids in todo), 0
    for key, ids in todo:
        scores = {}
        for label, node_id in ids.items():
            with CachedRenderer(variant_for(work, node_id), session, work.prepared, resolution,
                                period=period) as cached:
                errors = [float(mean_l2(cached.render_frame(ref.index).image, ref.image, ref.mask)[0])
                          for ref in reference]
            steady = errors[1:] or errors
            scores[label] = sum(steady) / len(steady)
            done += 1
            if progress is not None:
                progress(f"terms: {key} {label}", done, total)
        out[key] = scores
    return out


def scores_for(work, session, store, progress=None) -> dict:
    """The term scores of ``work`` for a profile: the ones its store kept (a resumed profile keeps
    its node ids), else measured now (:func:`measure_terms`) and kept."""
    import json

    kept = store.meta().get("term_scores")
    if kept is not None:
        return json.loads(kept)
    from rrcache.session.changes import per_frame_uniforms

    def say(detail, done, total):
        if progress is not None:
            from rrcache.profiler.train import ProgressEvent

            progress(ProgressEvent("terms", done, total, detail))

    scores = measure_terms(work, session, moving=sorted(per_frame_uniforms(session)), progress=say)
    store.set_meta("term_scores", json.dumps(scores))
    return scores
