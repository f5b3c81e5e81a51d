"""Print the order in which ``rrcache profile`` would train a shader's nodes, without measuring.

The order is the profiler's own (:func:`rrcache.profiler.train.training_order` with the default
:class:`~rrcache.profiles.TrainingSettings`): the nodes too cheap to win are left out, the others
ordered by what they depend on and their static cost. It reads the shader and the session and
renders nothing, so it runs in seconds; run it with ``PYTHONPATH`` set to another checkout to see
the order an older cost model gave (docs/costs.md does so for the IBL shader)::

    python tools/training_order.py shaders/ibl_gltf.glsl sessions/ibl.json --top 12
"""
from __future__ import annotations

import argparse
import json
import sys


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("shader")
    parser.add_argument("session")
    parser.add_argument("--top", type=int, default=10, help="rows to print (default 10; 0: all)")
    parser.add_argument("--find", action="append", default=[], metavar="TEXT",
                        help="also say the rank of the first node whose text contains TEXT (repeatable)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args(argv)

    from rrcache.pipeline import load_for_session
    from rrcache.profiler.train import training_order
    from rrcache.profiles import TrainingSettings
    from rrcache.session import load_session

    session = load_session(args.session)
    work = load_for_session(args.shader, session)
    order = training_order(work, session, TrainingSettings())
    rows = [{"rank": k + 1, "id": n.id, "cost": n.cost, "final": bool(getattr(n, "final", False)),
             "text": " ".join(n.text.split())} for k, n in enumerate(order.nodes)]
    found = {text: next((r["rank"] for r in rows if text in r["text"]), None) for text in args.find}
    summary = {"listed": len(work.table.nodes), "trained": len(rows), "too_cheap": len(order.skipped)}
    shown = rows if args.top == 0 else rows[:args.top]
    if args.json:
        json.dump({**summary, "order": shown, "found": found}, sys.stdout, indent=1)
        print()
        return 0
    print(f"{summary['listed']} nodes listed, {summary['trained']} to train, {summary['too_cheap']} too cheap to win")
    print(f"{'rank':>4}  {'id':<6} {'cost':>7}  text")
    for r in shown:
        text = r["text"] if len(r["text"]) <= 90 else r["text"][:87] + "..."
        print(f"{r['rank']:>4}  {r['id']:<6} {r['cost']:>7}  {text}{'  (final colour)' if r['final'] else ''}")
    for text, rank in found.items():
        print(f"first node containing {text!r}: " + (f"rank {rank}" if rank else "not trained"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
