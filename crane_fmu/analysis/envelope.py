"""The safety envelope's requirement (issue 51, item 2), measured on a board's scores.

In every case of every scenario a model-based controller's residual swing is no worse than the LQR's by more than
:data:`RESIDUAL_MARGIN`, and its peak swing is no more than :data:`PEAK_MARGIN` above its own peak on the nominal
move (S2: a faster move swings more on purpose; a wrong model must not add to it). Usage::

    crane-fmu compare --fmu-dir build/native --controller MpcController --controller LqrController --only \\
        --out results/envelope
    python -m crane_fmu.analysis.envelope results/envelope [--controller MpcController] [--reference LqrController]
"""

import argparse
from collections import defaultdict

RESIDUAL_MARGIN = 0.05  # deg
PEAK_MARGIN = 2.0  # deg
NOMINAL = "S2"


def violations(rows, controller="MpcController", reference="LqrController"):
    """Per scenario ``(cases, worse residual, higher peak, worst residual excess [deg])`` of ``controller``.

    ``rows``: the board's scores (dicts with ``controller``, ``scenario``, ``case``, ``residual_deg`` and
    ``peak_swing_deg``). The peak's bound needs the controller's S2 row; without it the peak is not judged (None).
    """
    figures = defaultdict(dict)
    for row in rows:
        if row["status"] == "ok":
            figures[row["controller"], row["scenario"]][row["case"]] = (row["residual_deg"], row["peak_swing_deg"])
    nominal = figures.get((controller, NOMINAL))
    peak_bound = max(peak for _, peak in nominal.values()) + PEAK_MARGIN if nominal else None
    out = {}
    for (name, scenario), cases in sorted(figures.items()):
        theirs = figures.get((reference, scenario), {})
        if name != controller or not theirs:
            continue
        paired = [(cases[k], theirs[k]) for k in cases if k in theirs]
        excess = [ours[0] - lqr[0] for ours, lqr in paired]
        worse = sum(e > RESIDUAL_MARGIN for e in excess)
        higher = None if peak_bound is None else sum(ours[1] > peak_bound for ours, _ in paired)
        out[scenario] = (len(paired), worse, higher, max(excess))
    return out, peak_bound


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", help="a board's folder (its scores.parquet)")
    p.add_argument("--controller", default="MpcController")
    p.add_argument("--reference", default="LqrController")
    args = p.parse_args(argv)
    import pyarrow.parquet as pq

    found, bound = violations(pq.read_table(f"{args.out}/scores.parquet").to_pylist(), args.controller,
                              args.reference)
    peak = f"its S2 peak + {PEAK_MARGIN:g} deg = {bound:.3f} deg" if bound is not None else "(no S2 run)"
    print(f"{args.controller} against {args.reference}: residual worse by > {RESIDUAL_MARGIN} deg; peak above {peak}")
    print("| scenario | cases | residual worse | peak higher | worst residual excess [deg] |")
    print("|---|---|---|---|---|")
    for scenario, (cases, worse, higher, excess) in found.items():
        print(f"| {scenario} | {cases} | {worse} | {'-' if higher is None else higher} | {excess:.4f} |")


if __name__ == "__main__":
    main()
