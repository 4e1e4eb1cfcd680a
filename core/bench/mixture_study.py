#!/usr/bin/env python3
"""The lobe mixture against LEAN on many real maps: `burnish evaluate --json` per map and power,
gathered into one table (Markdown on stdout, the rows as JSON with --json-out).

    core/bench/mixture_study.py BIN MAP... [--powers 64,256,1024] [--lobes 1,2,3,4] [--mips 1:4]
                                [--dense] [--between [--stochastic]] [--shaded-fit] [--energy-split]
                                [--json-out FILE]

For every map, power and mip it reads LEAN's and each mixture-kK row's relative L1 and energy ratio
and prints: per K the mean relative L1 over all (map, power, mip) cases next to LEAN's, the mean of
the per-case ratio to LEAN and its mean for each mip, the worst ratio (a case where the mixture is
worse than LEAN has a ratio above 1), the energy range and how many cases' energy ratios lie outside
[0.97, 1.03], and the per-map worst ratio. `--dense` evaluates with 1° half-angle
steps to 40° and 16 azimuths instead of the default 48 light/view pairs; `--shaded-fit` evaluates the
mixture fitted to the shaded ground truth too (evaluate --shaded-fit); `--stochastic` filters the mixture
after shading between texels (evaluate --mixture-filtering stochastic); `--energy-split` says where LEAN's
energy goes (evaluate --energy-split: its energy ratio as cosine x shape x steep) beside each K's energy,
per map, power and mip, and which step loses most how often. Bake and shading costs come from
the first map's report. Figures only: nothing here passes or fails.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile


def evaluate(binary, path, power, lobes, mips, dense, between, shaded=False, stochastic=False, split=False):
    first, last = mips
    with tempfile.TemporaryDirectory() as out:
        cmd = [binary, "evaluate", path, "--power", str(power), "--methods", "lean,mixture",
               "--lobes", ",".join(map(str, lobes)), "--first-mip", str(first), "--last-mip", str(last),
               "--bake-runs", "1", "--out", out, "--json", "--allow-implausible"]
        if dense:
            cmd += ["--half-angles", ",".join(str(a) for a in range(0, 41)), "--azimuths", "16"]
        if between:
            cmd += ["--between-texels"]
        if shaded:
            cmd += ["--shaded-fit"]
        if stochastic:
            cmd += ["--mixture-filtering", "stochastic"]
        if split:
            cmd += ["--energy-split"]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            print(f"skipped {path} s={power}: {run.stderr.strip().splitlines()[-1]}", file=sys.stderr)
            return None
        return json.loads(run.stdout)


def summary(rows, lobes, suffix):
    """LEAN's and each K's row of the summary table, from the fields lean<suffix>, k<K><suffix> and
    their _energy ones (suffix "" for the aligned figures, "_between" between texels)."""
    mips = sorted({r["mip"] for r in rows})
    print("| method | mean rel. L1 | median | mean ratio to LEAN | ratio, mips " + " / ".join(map(str, mips)) +
          " | worst ratio | cases worse than LEAN | energy min | energy max | outside [0.97, 1.03] |")
    print("| --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: |")
    for name, key in [("lean", "lean")] + [(f"mixture-k{k}", f"k{k}") for k in lobes]:
        v = [r[key + suffix] for r in rows]
        ratio = [r[key + suffix] / r["lean" + suffix] if r["lean" + suffix] > 0 else 1.0 for r in rows]
        en = [r[key + suffix + "_energy"] for r in rows]
        worse = sum(1 for x in ratio if x > 1.0)
        outside = sum(1 for e in en if not 0.97 <= e <= 1.03)
        by_mip = " / ".join(f"{statistics.mean(x for x, r in zip(ratio, rows) if r['mip'] == m):.2f}" for m in mips)
        print(f"| {name} | {statistics.mean(v):.4f} | {statistics.median(v):.4f} | {statistics.mean(ratio):.3f} | "
              f"{by_mip} | {max(ratio):.3f} | {worse} | {min(en):.3f} | {max(en):.3f} | {outside} |")


def energy_split(rows, lobes, powers):
    """Where LEAN's energy goes: per power a row per map and mip (LEAN's energy = cosine x shape x steep,
    the share of steep normals, each K's energy), then how often each step is the largest loss."""
    steps = ("cosine", "shape", "steep")
    for s in powers:
        rs = [r for r in rows if r["power"] == s and "split_steep" in r]
        if not rs:
            continue
        print(f"\nWhere LEAN's energy goes at s = {s:g} (energy = cosine x shape x steep; steep: tilted more "
              "than evaluate's --steep-deg, 45 deg):\n")
        print("| map | steep normals | mip | LEAN energy | cosine | shape | steep | "
              + " | ".join(f"k{k} energy" for k in lobes) + " |")
        print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | " + " | ".join("---:" for _ in lobes) + " |")
        for r in rs:
            print(f"| {r['map']} | {100 * r['split_steep_normals']:.1f} % | {r['mip']} | {r['lean_energy']:.3f} | "
                  + " | ".join(f"{r['split_' + k]:.3f}" for k in steps) + " | "
                  + " | ".join(f"{r[f'k{k}_energy']:.3f}" for k in lobes) + " |")
    rs = [r for r in rows if "split_steep" in r]
    if not rs:
        return
    print("\nThe step that loses most (the smallest factor below 1), over every case:\n")
    print("| LEAN's energy | cases | " + " | ".join(f"{k} loses most" for k in steps) + " | none below 0.97 |")
    print("| --- | ---: | " + " | ".join("---:" for _ in steps) + " | ---: |")
    for name, lo, hi in (("below 0.97", 0.0, 0.97), ("0.97 and above", 0.97, float("inf"))):
        group = [r for r in rs if lo <= r["lean_energy"] < hi]
        counts = {k: 0 for k in steps}
        none = 0
        for r in group:
            worst = min(steps, key=lambda k: r["split_" + k])
            if r["split_" + worst] < 0.97:
                counts[worst] += 1
            else:
                none += 1
        print(f"| {name} | {len(group)} | " + " | ".join(str(counts[k]) for k in steps) + f" | {none} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binary")
    ap.add_argument("maps", nargs="+")
    ap.add_argument("--powers", default="64,256,1024")
    ap.add_argument("--lobes", default="1,2,3,4")
    ap.add_argument("--mips", default="1:4")
    ap.add_argument("--dense", action="store_true")
    ap.add_argument("--between", action="store_true", help="also evaluate between texels (--between-texels)")
    ap.add_argument("--shaded-fit", action="store_true",
                    help="the mixture fitted to the shaded ground truth too (evaluate --shaded-fit)")
    ap.add_argument("--stochastic", action="store_true",
                    help="between texels, the mixture filtered after shading (evaluate --mixture-filtering stochastic)")
    ap.add_argument("--energy-split", action="store_true",
                    help="where LEAN's energy goes, beside the mixture's (evaluate --energy-split)")
    ap.add_argument("--json-out")
    a = ap.parse_args()
    powers = [float(p) for p in a.powers.split(",")]
    lobes = [int(k) for k in a.lobes.split(",")]
    mips = tuple(int(m) for m in a.mips.split(":"))

    rows, costs = [], None
    for path in a.maps:
        for s in powers:
            report = evaluate(a.binary, path, s, lobes, mips, a.dense, a.between, a.shaded_fit, a.stochastic,
                              a.energy_split)
            if report is None:
                continue
            if costs is None:
                costs = report["costs"]
            by = {(e["variant"], e["mip"]): e for e in report["errors"] if not e.get("between_texels")}
            between = {(e["variant"], e["mip"]): e for e in report["errors"] if e.get("between_texels")}
            split = {e["mip"]: e for e in report.get("lean_energy_split", [])}
            for mip in range(mips[0], mips[1] + 1):
                lean = by.get(("lean", mip))
                if lean is None:
                    continue
                row = {"map": os.path.basename(path), "size": f'{report["width"]}x{report["height"]}',
                       "power": s, "mip": mip, "lean": lean["relative_l1"], "lean_energy": lean["energy_ratio"]}
                for k in lobes:
                    e = by[(f"mixture-k{k}", mip)]
                    row[f"k{k}"] = e["relative_l1"]
                    row[f"k{k}_energy"] = e["energy_ratio"]
                    if between:
                        row[f"k{k}_between"] = between[(f"mixture-k{k}", mip)]["relative_l1"]
                        row[f"k{k}_between_energy"] = between[(f"mixture-k{k}", mip)]["energy_ratio"]
                if mip in split:
                    for key in ("cosine", "shape", "steep", "steep_normals", "steep_truth"):
                        row["split_" + key] = split[mip][key]
                if between:
                    row["lean_between"] = between[("lean", mip)]["relative_l1"]
                    row["lean_between_energy"] = between[("lean", mip)]["energy_ratio"]
                rows.append(row)
            print(f"done {path} s={s:g}", file=sys.stderr)
    if not rows:
        sys.exit("no case evaluated")

    maps = sorted({r["map"] for r in rows})
    print(f"{len(maps)} maps, powers {a.powers}, mips {a.mips}, {len(rows)} cases"
          f"{' (dense directions: 0..40 deg every 1 deg x 16 azimuths)' if a.dense else ''}\n")
    summary(rows, lobes, "")
    print("\nPer map, the worst ratio to LEAN over powers and mips (and LEAN's mean rel. L1):\n")
    print("| map | size | lean | " + " | ".join(f"k{k}" for k in lobes) + " |")
    print("| --- | --- | ---: | " + " | ".join("---:" for _ in lobes) + " |")
    for m in maps:
        rs = [r for r in rows if r["map"] == m]
        worst = [max(r[f"k{k}"] / r["lean"] if r["lean"] > 0 else 1.0 for r in rs) for k in lobes]
        print(f"| {m} | {rs[0]['size']} | {statistics.mean(r['lean'] for r in rs):.4f} | "
              + " | ".join(f"{w:.3f}" for w in worst) + " |")
    if a.energy_split:
        energy_split(rows, lobes, powers)
    if a.between:
        print("\nBetween texels (--between-texels):\n")
        summary(rows, lobes, "_between")
    if costs:
        print("\nCost (first map):\n")
        print("| method | bake s | shading ns/lobe | fetches | bytes/texel |")
        print("| --- | ---: | ---: | ---: | ---: |")
        for c in costs:
            print(f"| {c['variant']} | {c['bake_seconds_median']:.3g} | {c['shading_ns_per_lobe']:.3g} | "
                  f"{c['texture_fetches']} | {c['bytes_per_texel']:g} |")
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump({"rows": rows, "costs": costs}, f, indent=1)


if __name__ == "__main__":
    main()
