"""The 8-bit payload of an amortized ``slots`` variant: its values encoded into [0, 1].

An RGBA8 (unsigned normalised) payload is read and filtered much faster than a 32-bit float one
by a software rasteriser (llvmpipe filters 8-bit texels on a fast fixed-point path: on the PCF
temple, Catmull-Rom down the screen went from 1.87x to 2.09x the original's speed, measured side
by side; README, "Amortized sampling"), and it is a quarter of the memory traffic on a GPU. It
needs the range of what it stores. A ``slots`` payload holds subset sums of ``m`` of the
estimator's terms (without the accumulators' start value), each blended with its reprojected
self by ``λ``, and the filters only mix neighbouring values (bilinear with convex weights; the
Catmull-Rom filters clamp to the taps' range): so when every term lies in ``[lo, hi]``
(:attr:`rrcache.analysis.estimators.Estimator.term_range`, proven by the analysis or declared
with ``#pragma rrcache estimator range(LO, HI)``), every slot lies in ``[m·lo, m·hi]``, and the
passes write ``(v − m·lo) / (m·(hi − lo))``. The ``blend`` history stores the whole accumulator
(its start value included, which the analysis does not bound), so it keeps a float payload.

The encoding is affine and increasing per channel, so decoding after the filter equals
filtering the decoded values: reads are ``rr_decode(rr_previous())``. What is lost is the
rounding to 1/255 of the slot's range at every frame's write (measured, not modelled: the
error runs and ``rrcache bench-amortize`` see it).

>>> e = slots_encoding((0.0, 1.0), samples=4, slots=4, components=1)
>>> e.offset, e.span
((0.0, 0.0, 0.0, 0.0), (4.0, 4.0, 4.0, 4.0))
>>> slots_encoding((-1.0, 1.0), samples=2, slots=2, components=1).span
(4.0, 4.0, 1.0, 1.0)
"""
from __future__ import annotations

from dataclasses import dataclass

from rrcache.analysis.term_range import FLT_MAX
from rrcache.glsl import ast as A

__all__ = ["PayloadEncoding", "slots_encoding", "encoding_glsl", "encoded", "decoded", "ENCODED_DTYPE"]

#: the payload format that stores encoded values (rrcache.runtime.cache.RUNTIME_PAYLOAD_DTYPES)
ENCODED_DTYPE = "u8"


@dataclass(frozen=True)
class PayloadEncoding:
    """Per payload channel: stored = (value − offset) / span; unused channels offset 0, span 1."""

    offset: tuple[float, float, float, float]
    span: tuple[float, float, float, float]

    def to_json(self) -> dict:
        return {"offset": list(self.offset), "span": list(self.span)}


def slots_encoding(term_range: tuple[float, float], samples: int, slots: int, components: int) -> PayloadEncoding:
    """The encoding of ``slots`` subset sums of ``samples`` terms each in ``term_range``, every
    slot ``components`` channels wide (the accumulators'), in channel order."""
    lo, hi = float(term_range[0]), float(term_range[1])
    if not hi >= lo:
        raise ValueError(f"a term range needs lo <= hi, not [{lo:g}, {hi:g}]")
    used = slots * components
    if used > 4:
        raise ValueError(f"{slots} slots of {components} component(s) do not fit in 4 channels")
    if max(abs(samples * lo), abs(samples * hi), samples * (hi - lo)) > FLT_MAX:
        raise ValueError(f"{samples} terms in [{lo:g}, {hi:g}] sum beyond the 32-bit float range")
    offset = [samples * lo] * used + [0.0] * (4 - used)
    # a constant term (lo = hi, or a span too small for its inverse to be a 32-bit float):
    # every slot is samples * lo, stored as 0
    span = [samples * (hi - lo) if samples * (hi - lo) > 1e-30 else 1.0] * used + [1.0] * (4 - used)
    return PayloadEncoding(tuple(offset), tuple(span))


def _vec4(values) -> str:
    return "vec4(" + ", ".join(repr(float(v)) for v in values) + ")"


def encoding_glsl(enc: PayloadEncoding) -> str:
    """The runtime snippet: ``rr_encode`` (before a payload write) and ``rr_decode`` (after a read)."""
    inverse = [1.0 / s for s in enc.span]
    return (f"const vec4 rr_payloadOffset = {_vec4(enc.offset)};\n"
            f"const vec4 rr_payloadSpan = {_vec4(enc.span)};\n"
            f"const vec4 rr_payloadInvSpan = {_vec4(inverse)};\n"
            "vec4 rr_encode(vec4 v) { return (v - rr_payloadOffset) * rr_payloadInvSpan; }\n"
            "vec4 rr_decode(vec4 v) { return v * rr_payloadSpan + rr_payloadOffset; }\n")


def encoded(value: A.Expr) -> A.Expr:
    """``rr_encode(value)``"""
    return A.Call("rr_encode", [value])


def decoded(read: A.Expr) -> A.Expr:
    """``rr_decode(read)``"""
    return A.Call("rr_decode", [read])
