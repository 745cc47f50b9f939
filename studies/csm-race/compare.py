#!/usr/bin/env python3
"""A C matcher's race output (race_csm, race_mbicp) against the project's matchers, row by row.

    compare.py [--like MATCHER] SEED_RUN [SEED_RUN ...]

Each SEED_RUN is MATCHERS_DIR:RACE_DIR:C_CSV for one seed:
  MATCHERS_DIR  the --out of `twin matchers --matchers lorentz-lines,MATCHER --seed S`
                (its pairs.csv: the project's answers and successes);
  RACE_DIR      the RACE_CSV of `RACE_SEED=S cargo bench --bench matcher_race` (each pair's
                best times of lorentz-lines and pl-icp), or - to leave times out;
  C_CSV         the C race's output on the same seed's pairs.
Success and the median errors are pooled over the runs; times are each run's median pair, given
as the range over runs.
MATCHER (default pl-icp) is the project's matcher whose answers are compared with the C code's
(within 1 mm and 0.01 deg). Prints a Markdown table. Standard library only.
"""
import csv
import math
import os
import sys


def fail(message):
    sys.exit(f"compare.py: {message}")


def read_csv(path):
    try:
        with open(path, newline="", encoding="utf-8") as f:
            return list(csv.DictReader(f))
    except OSError as e:
        fail(f"cannot read {path}: {e}")


def median(values):
    return sorted(values)[len(values) // 2]


def span(values, digits):
    if not values:
        return "–"
    lo, hi = min(values), max(values)
    return f"{lo:.{digits}f}" if lo == hi else f"{lo:.{digits}f}–{hi:.{digits}f}"


def micros(values):
    return f"{span(values, 0)} µs" if values else "–"


def main(argv):
    args = argv[1:]
    like = "pl-icp"
    if args[:1] == ["--like"]:
        if len(args) < 2:
            fail("--like needs a matcher's name")
        like, args = args[1], args[2:]
    if not args:
        fail("usage: compare.py [--like MATCHER] MATCHERS_DIR:RACE_DIR:C_CSV ...")
    stats, order = {}, []
    for run in args:
        parts = run.split(":")
        if len(parts) != 3:
            fail(f"{run!r}: expected MATCHERS_DIR:RACE_DIR:C_CSV")
        matchers_dir, race_dir, c_csv = parts
        ours, seeds = {}, set()
        pairs_csv = os.path.join(matchers_dir, "pairs.csv")
        for r in read_csv(pairs_csv):
            seeds.add(r["seed"])
            ours[(r["set"].replace(" ", "_"), int(r["pair"]), r["matcher"])] = r
        if len(seeds) > 1:
            fail(f"{pairs_csv} holds the answers of seeds {', '.join(sorted(seeds, key=int))}: "
                 "give one `twin matchers --seed S` run for each C run")
        c_rows = {}
        for line, r in enumerate(read_csv(c_csv), start=2):
            try:
                c_rows.setdefault(r["row"], {})[int(r["pair"])] = r
                # An answer may be NaN (a C matcher that failed so): its error counts as infinite.
                for field in ("micros", "x", "y", "theta", "error_m"):
                    float(r[field])
                if not math.isfinite(float(r["micros"])):
                    raise ValueError(f"micros is {r['micros']}")
                int(r["success"])
            except (KeyError, ValueError, TypeError) as e:
                fail(f"{c_csv}, line {line}: expected row,pair,micros,valid,x,y,theta,iterations,"
                     f"error_m,error_rad,success: {e}")
        if not c_rows:
            fail(f"{c_csv}: no pairs (expected the output of race_csm or race_mbicp)")
        for row, pairs in c_rows.items():
            if row not in stats:
                order.append(row)
                stats[row] = {"n": 0, "c": 0, "ll": 0, "like": 0, "alike": 0, "c_err": [], "ll_err": [],
                              "c_med": [], "ll_med": [], "ratio": [], "whole": []}
            s = stats[row]
            for p, k in pairs.items():
                try:
                    o, ll = ours[(row, p, like)], ours[(row, p, "lorentz-lines")]
                except KeyError:
                    fail(f"{matchers_dir}/pairs.csv has no {like} or lorentz-lines answer to {row} pair {p}")
                s["n"] += 1
                s["c"] += int(k["success"])
                s["ll"] += int(ll["success"])
                c_err = float(k["error_m"]) * 1e3
                s["c_err"].append(c_err if math.isfinite(c_err) else math.inf)
                s["ll_err"].append(float(ll["error_mm"]))
                s["like"] += int(o["success"])
                dxy = math.hypot(float(o["x_m"]) - float(k["x"]), float(o["y_m"]) - float(k["y"]))
                dth = math.remainder(math.radians(float(o["theta_deg"])) - float(k["theta"]), 2 * math.pi)
                s["alike"] += dxy <= 1e-3 and abs(dth) <= math.radians(0.01)
            if race_dir != "-":
                race_file = os.path.join(race_dir, row.replace(",", "_").replace("/", "_") + ".csv")
                race = {int(r["pair"]): float(r["lorentz_lines_us"]) for r in read_csv(race_file)}
                missing = [p for p in pairs if p not in race]
                if missing:
                    fail(f"{race_file} lacks pairs {missing[:5]}")
                c = [float(pairs[p]["micros"]) for p in sorted(pairs)]
                l = [race[p] for p in sorted(pairs)]
                s["c_med"].append(median(c))
                s["ll_med"].append(median(l))
                s["ratio"].append(median(l) / median(c))
                s["whole"].append(sum(l) / sum(c))
    print(f"| row | pairs | C success | lorentz-lines success | {like} success | answered alike as {like} "
          "| median error, C / lorentz-lines | C median pair | lorentz-lines median pair | ratio of medians "
          "| whole row |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for row in order:
        s = stats[row]
        n = s["n"]
        print(f"| {row.replace('_', ' ')} | {n} | {s['c'] / n:.4f} | {s['ll'] / n:.4f} | {s['like'] / n:.4f} "
              f"| {s['alike'] / n:.2f} | {median(s['c_err']):.2f} / {median(s['ll_err']):.2f} mm "
              f"| {micros(s['c_med'])} | {micros(s['ll_med'])} "
              f"| {span(s['ratio'], 3)} | {span(s['whole'], 3)} |")


if __name__ == "__main__":
    main(sys.argv)
