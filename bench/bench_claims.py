"""Each paper's headline claim over several seeds (`tactip.reproduce.seeds`): margins, 95 % interval, verdict.

Runs ``tactip reproduce P --quick --seed S`` (or the full size with --full) for every paper and seed and
judges each claim from its margins' interval, never from one seed (issue 25's bars). A claim's variants
(`tactip.reproduce.seeds.VARIANTS`) are judged beside it, never instead of it.

    python bench/bench_claims.py [--papers 000 001 002 003 004] [--seeds 0 1 2] [--full] [--per-seed] [--json OUT]

Last measured for 002 (quick, seeds 0-9, 2026-11-29, `TACTIP_SIM_WORKERS=1`, 281 s of CPU): active fixated
as the paper chose (the Fig. 10 sweep's best within 12 mean taps on the test collection) holds, margin
0.0438 mm, 95 % interval 0.0263 to 0.0613, held on 10 of 10 seeds; the variant, active at the station's own
fixation (chosen on held-out training taps), partly holds: 0.0274 mm, -0.0003 to 0.0552, 9 of 10 (seed 2,
-0.056 mm: its 4.75 mm is poor on the test taps; `tactip/reproduce/p002.py` says why). Full size (--full, seeds
0-9, 126-139 s of CPU a seed): holds, 0.0242 mm, 0.0199 to 0.0285, 10 of 10; the variant partly holds, 0.0153,
0.0073 to 0.0233, 9 of 10 (seed 9, -0.007 mm).
"""

from __future__ import annotations

import argparse
import json
import time


def main() -> None:
    """Run the papers over the seeds and print one verdict per claim."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--papers", nargs="+", default=["000", "001", "002", "003", "004"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--full", action="store_true", help="full-size runs (minutes each) instead of --quick")
    parser.add_argument("--json", help="write the verdicts as JSON (a variant's with its name under 'variant')")
    parser.add_argument("--per-seed", action="store_true", help="print each seed's margin as it comes")
    args = parser.parse_args()

    from tactip.reproduce import reproduce
    from tactip.reproduce.seeds import VARIANTS, judge_claim

    verdicts = []
    for paper in args.papers:
        started, cpu = time.monotonic(), time.process_time()
        rows = {}
        for seed in args.seeds:
            rows[seed] = reproduce(paper, quick=not args.full, seed=seed).rows
            if args.per_seed:
                print(f"  seed {seed}: margin {judge_claim(paper, {seed: rows[seed]}).mean:.4g}" + "".join(
                    f", variant {judge_claim(paper, {seed: read(rows[seed])}).mean:.4g}"
                    for _, read in VARIANTS.get(paper, ())), flush=True)
        verdict = judge_claim(paper, rows)
        verdicts.append(verdict.json())
        margins = ", ".join(f"{m:.3g}" for m in verdict.margins)
        print(f"paper {paper} ({time.monotonic() - started:.0f} s, {time.process_time() - cpu:.0f} s CPU, seeds "
              f"{', '.join(map(str, args.seeds))}; margins {margins})\n{verdict.line()}", flush=True)
        for name, read in VARIANTS.get(paper, ()):        # beside the claim, never instead of it
            variant = judge_claim(paper, {seed: read(r) for seed, r in rows.items()})
            verdicts.append(dict(variant.json(), variant=name))
            print(f"  variant {name}: margins {', '.join(f'{m:.3g}' for m in variant.margins)}\n  {variant.line()}",
                  flush=True)
    if args.json:
        with open(args.json, "w") as out:
            json.dump(verdicts, out, indent=1)


if __name__ == "__main__":
    main()
