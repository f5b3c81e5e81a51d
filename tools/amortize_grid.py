"""The m × λ error grid of an estimator against the original (the measurements behind the error
model of rrcache/model/amortize.py; README, "Amortized sampling"). Usage:

    python tools/amortize_grid.py SHADER SESSION WxH FRAMES M_LIST LAMBDA_LIST OUT.json
"""
import sys, json, numpy as np
from rrcache.pipeline import load_for_session
from rrcache.session import load_session
from rrcache.compiler.amortize import instance_amortized
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.renderer import Renderer
from rrcache.harness.metrics import mean_l2
shader, sess, res, frames, ms, lams = sys.argv[1], sys.argv[2], tuple(map(int, sys.argv[3].split("x"))), int(sys.argv[4]), [int(x) for x in sys.argv[5].split(",")], [float(x) for x in sys.argv[6].split(",")]
session = load_session(sess)
work = load_for_session(shader, session)
refs = []
with Renderer(work.prepared, session, res) as r:
    for i in range(frames):
        refs.append(r.render_frame(i))
out = {}
for m in ms:
    v = instance_amortized(work.shader, "e1", "two-pass", samples=m, blend=0.0, vertex=work.vertex)
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
json.dump(out, open(sys.argv[7], "w"))
