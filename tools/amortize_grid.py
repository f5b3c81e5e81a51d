"""The m × λ error grid of an estimator against the original (the measurements behind the error
models of rrcache/model/amortize.py; docs/amortize_model_grid.json). Usage:

    python tools/amortize_grid.py SHADER SESSION WxH FRAMES M_LIST LAMBDA_LIST OUT.json \
        [--history blend|slots] [-D NAME=VALUE ...]

``--history slots`` measures the variant that keeps the N/m subset sums apart (only the m where
they fit the payload: :func:`rrcache.compiler.amortize.slots_fit`); ``-D`` sets a define (e.g.
``PCF_SAMPLES=12`` for another N).
"""
import argparse
import json

import numpy as np

from rrcache.compiler.amortize import instance_amortized
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.metrics import mean_l2
from rrcache.harness.renderer import Renderer
from rrcache.pipeline import load_for_session
from rrcache.session import load_session

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("shader")
parser.add_argument("session")
parser.add_argument("resolution")
parser.add_argument("frames", type=int)
parser.add_argument("samples")
parser.add_argument("blends")
parser.add_argument("out")
parser.add_argument("--history", choices=("blend", "slots"), default="blend")
parser.add_argument("-D", dest="defines", action="append", default=[])
args = parser.parse_args()
res = tuple(map(int, args.resolution.split("x")))
ms = [int(x) for x in args.samples.split(",")]
lams = [float(x) for x in args.blends.split(",")]
defines = dict(d.split("=", 1) for d in args.defines)
session = load_session(args.session)
work = load_for_session(args.shader, session, defines or None)
refs = []
with Renderer(work.prepared, session, res) as r:
    for i in range(args.frames):
        refs.append(r.render_frame(i))
out = {}
for m in ms:
    v = instance_amortized(work.shader, "e1", "two-pass", samples=m, blend=0.0, history=args.history,
                           vertex=work.vertex)
    with CachedRenderer(v, session, work.prepared, res, period=2**30) as c:
        for lam in lams:
            c.runtime.blend = lam
            c.reset()
            errs = []
            for ref in refs:
                got = c.render_frame(ref.index)
                errs.append(float(mean_l2(got.image, ref.image, ref.mask)[0]))
            out[f"{m},{lam}"] = float(np.mean(errs[1:]))
            print(m, lam, out[f"{m},{lam}"], flush=True)
with open(args.out, "w") as f:
    json.dump(out, f)
