#!/usr/bin/env python3
"""CSM's C point-to-line ICP against the project's matchers, row by row, on one seed's pairs.

    compare.py MATCHERS_DIR RACE_DIR CSM_CSV [CSM_CSV ...]

MATCHERS_DIR: the --out of `twin matchers --matchers pl-icp --seed S` (its pairs.csv gives the
project's pl-icp answers); RACE_DIR: the RACE_CSV of `RACE_SEED=S cargo bench --bench
matcher_race` (each pair's best times of lorentz-lines and pl-icp); CSM_CSV: race.c's output
on the same seed's pairs (several: each pair's best time of them). Prints a Markdown table:
CSM's and pl-icp's success, how many pairs the two answer alike (within 1 mm and 0.01 deg),
CSM's and lorentz-lines' median pair, their ratio, the ratio of their times summed over the
row, and pl-icp's median pair against CSM's. Standard library only.
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


def main(argv):
    if len(argv) < 4:
        fail(__doc__.strip().splitlines()[2].strip())
    matchers_dir, race_dir, csm_files = argv[1], argv[2], argv[3:]
    ours = {}
    for r in read_csv(os.path.join(matchers_dir, "pairs.csv")):
        if r["matcher"] == "pl-icp":
            ours[(r["set"].replace(" ", "_"), int(r["pair"]))] = r
    csm, rows = {}, []
    for path in csm_files:
        for line, r in enumerate(read_csv(path), start=2):
            try:
                key, micros = (r["row"], int(r["pair"])), float(r["micros"])
            except (KeyError, ValueError) as e:
                fail(f"{path}, line {line}: expected row,pair,micros,...: {e}")
            if key[0] not in rows:
                rows.append(key[0])
            if key in csm:
                csm[key]["micros"] = min(csm[key]["micros"], micros)
            else:
                csm[key] = dict(r, micros=micros)
    print("| row | CSM success | pl-icp success | answered alike | CSM median pair "
          "| lorentz-lines median pair | ratio | whole row | pl-icp median / CSM's |")
    print("|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        race_file = os.path.join(race_dir, row.replace(",", "_").replace("/", "_") + ".csv")
        race = {int(r["pair"]): r for r in read_csv(race_file)}
        pairs = sorted(p for (name, p) in csm if name == row)
        missing = [p for p in pairs if p not in race or (row, p) not in ours]
        if missing:
            fail(f"row {row}: pairs {missing[:5]} are not in {race_file} or in pairs.csv")
        c = [csm[(row, p)]["micros"] for p in pairs]
        ll = [float(race[p]["lorentz_lines_us"]) for p in pairs]
        pl = [float(race[p]["pl_icp_us"]) for p in pairs]
        alike = 0
        for p in pairs:
            o, k = ours[(row, p)], csm[(row, p)]
            dxy = math.hypot(float(o["x_m"]) - float(k["x"]), float(o["y_m"]) - float(k["y"]))
            dth = math.remainder(math.radians(float(o["theta_deg"])) - float(k["theta"]), 2 * math.pi)
            alike += dxy <= 1e-3 and abs(dth) <= math.radians(0.01)
        n = len(pairs)
        csm_success = sum(int(csm[(row, p)]["success"]) for p in pairs) / n
        pl_success = sum(int(ours[(row, p)]["success"]) for p in pairs) / n
        print(f"| {row.replace('_', ' ')} | {csm_success:.4f} | {pl_success:.4f} | {alike}/{n} "
              f"| {median(c):.0f} µs | {median(ll):.0f} µs | {median(ll) / median(c):.3f} "
              f"| {sum(ll) / sum(c):.3f} | {median(pl) / median(c):.3f} |")


if __name__ == "__main__":
    main(sys.argv)
