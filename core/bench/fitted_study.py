#!/usr/bin/env python3
"""The fitted one-lobe roughness against the engine's default (naive), vMF and variance-to-gloss under
the GGX truth an engine shades, on many real maps: `burnish evaluate --brdf ggx --floor --json` per map
and power, gathered into one table. Figures only: nothing here passes or fails, but each target of the
fitted lobe is printed with its count of cases that miss it.

    core/bench/fitted_study.py BIN MAP... [--powers 64,256,1024] [--mips 1:6] [--json-out FILE]

Per case (map, power, mip) it reads the relative L1 and energy of naive, vmf, variance-to-gloss, fitted
and the one-lobe floor (the best single isotropic roughness per texel by brute force), and prints:
  - every case where fitted > min(naive, vmf) + 0.01, and its count;
  - fitted against the floor: worst ratio, and how many cases lie more than 2 % above it;
  - the mean relative L1 at mips 3-6 of each method, and its ratio to naive's (the floor's own ratio
    says how far one lobe can go);
  - the mean |1 - energy| of each method;
  - per map: naive / vmf / fitted / floor at the last mip, and fitted's mean ratio to naive.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

METHODS = ["naive", "variance-to-gloss", "vmf", "fitted"]
FLOOR = "one-lobe floor"
ANISO = "fitted anisotropic"


def evaluate(binary, path, power, mips, anisotropic=False):
    first, last = mips
    with tempfile.TemporaryDirectory() as out:
        cmd = [binary, "evaluate", path, "--brdf", "ggx", "--floor", "--power", str(power), "--methods",
               ",".join(METHODS), "--first-mip", str(first), "--last-mip", str(last), "--bake-runs", "1",
               "--out", out, "--json", "--allow-implausible"] + (["--anisotropic"] if anisotropic else [])
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            print(f"skipped {path} s={power}: {run.stderr.strip().splitlines()[-1]}", file=sys.stderr)
            return None
        return json.loads(run.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binary")
    ap.add_argument("maps", nargs="+")
    ap.add_argument("--powers", default="64,256,1024")
    ap.add_argument("--mips", default="1:6")
    ap.add_argument("--json-out")
    ap.add_argument("--anisotropic", action="store_true",
                    help="add the anisotropic fit (KHR_materials_anisotropy's pair, as engines shade it) and "
                         "per map the better of it and the isotropic fit over all its cases")
    args = ap.parse_args()
    powers = [float(p) for p in args.powers.split(",")]
    mips = tuple(int(m) for m in args.mips.split(":"))

    rows = []  # one per (map, power, mip): {method: (relL1, energy)}
    for path in args.maps:
        for s in powers:
            report = evaluate(args.binary, path, s, mips, args.anisotropic)
            if report is None:
                continue
            cases = {}
            for e in report["errors"]:
                if e.get("between_texels") or e.get("kernel", "box") != "box":
                    continue
                name = e["variant"]
                cases.setdefault(int(e["mip"]), {})[name] = (e["relative_l1"], e["energy_ratio"])
            for mip, values in sorted(cases.items()):
                rows.append({"map": os.path.basename(path), "power": s, "mip": mip, "values": values})
    if not rows:
        sys.exit("no case evaluated")
    names = METHODS + [FLOOR] + ([ANISO] if args.anisotropic else [])
    maps = sorted({r["map"] for r in rows})
    print(f"{len(maps)} maps, powers {args.powers}, mips {args.mips}: {len(rows)} cases (GGX truth, "
          f"evaluate's 48 light/view pairs)\n")

    # Target 1: never worse than the better of naive and vmf beyond 0.01.
    misses = [r for r in rows
              if r["values"]["fitted"][0] > min(r["values"]["naive"][0], r["values"]["vmf"][0]) + 0.01]
    print(f"fitted > min(naive, vmf) + 0.01: {len(misses)} of {len(rows)} cases")
    for r in misses:
        v = r["values"]
        print(f"  {r['map']} s={r['power']:g} mip {r['mip']}: fitted {v['fitted'][0]:.4f}, naive "
              f"{v['naive'][0]:.4f}, vmf {v['vmf'][0]:.4f}")
    # Target 2: within 2 % of the floor.
    ratios = [(r["values"]["fitted"][0] / r["values"][FLOOR][0] if r["values"][FLOOR][0] > 0 else 1.0, r)
              for r in rows]
    worst = max(ratios, key=lambda x: x[0])
    over = sum(1 for q, _ in ratios if q > 1.02)
    print(f"fitted / floor: mean {statistics.mean(q for q, _ in ratios):.4f}, worst {worst[0]:.4f} "
          f"({worst[1]['map']} s={worst[1]['power']:g} mip {worst[1]['mip']}); more than 2 % above: {over}\n")

    # Target 3: the mean at mips 3-6 against naive's, beside the floor's own ratio.
    late = [r for r in rows if 3 <= r["mip"] <= 6]
    print("| method | mean rel. L1, mips 1-6 | mean rel. L1, mips 3-6 | ratio to naive, mips 3-6 | "
          "mean abs(1 - energy) | worse than naive (cases) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    naive_late = statistics.mean(r["values"]["naive"][0] for r in late) if late else float("nan")
    summary = {}
    for m in names:
        all_mean = statistics.mean(r["values"][m][0] for r in rows)
        late_mean = statistics.mean(r["values"][m][0] for r in late) if late else float("nan")
        energy = (statistics.mean(abs(1.0 - r["values"][m][1]) for r in rows) if m != FLOOR else
                  statistics.mean(abs(1.0 - r["values"][m][1]) for r in rows))
        worse = sum(1 for r in rows if r["values"][m][0] > r["values"]["naive"][0] + 1e-12)
        summary[m] = {"mean": all_mean, "mean_late": late_mean, "ratio_late": late_mean / naive_late,
                      "energy_dev": energy, "worse_than_naive": worse}
        print(f"| {m} | {all_mean:.4f} | {late_mean:.4f} | {late_mean / naive_late:.3f} | {energy:.4f} | {worse} |")

    print("\nPer map (mean over powers; last mip's relative L1 and the mean ratio to naive over mips 3-6):\n")
    print("| map | naive | vmf | variance-to-gloss | fitted | floor | fitted / naive, mips 3-6 | floor / naive |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    last = max(r["mip"] for r in rows)
    for name in maps:
        mine = [r for r in rows if r["map"] == name]
        top = max(r["mip"] for r in mine)
        at = [r for r in mine if r["mip"] == top]
        cells = [statistics.mean(r["values"][m][0] for r in at) for m in ["naive", "vmf", "variance-to-gloss",
                                                                         "fitted", FLOOR]]
        lm = [r for r in mine if 3 <= r["mip"] <= 6] or mine
        nm = statistics.mean(r["values"]["naive"][0] for r in lm)
        fr = statistics.mean(r["values"]["fitted"][0] for r in lm) / nm if nm > 0 else 1.0
        fl = statistics.mean(r["values"][FLOOR][0] for r in lm) / nm if nm > 0 else 1.0
        suffix = "" if top == last else f" (mip {top})"
        print(f"| {name}{suffix} | " + " | ".join(f"{c:.4f}" for c in cells) + f" | {fr:.3f} | {fl:.3f} |")
    if args.anisotropic:
        # A material turns KHR_materials_anisotropy on or off for all its texels: per map, which wins over
        # all its cases, and what choosing the better one per map gives.
        print("\nAnisotropic (KHR_materials_anisotropy on: every texel shaded by the anisotropic form) against "
              "the isotropic fit, per map over its powers and mips:\n")
        print("| map | fitted | fitted anisotropic | anisotropic / fitted | mips where anisotropic wins |")
        print("| --- | ---: | ---: | ---: | --- |")
        chosen, better = [], 0
        for name in maps:
            mine = [r for r in rows if r["map"] == name]
            f = statistics.mean(r["values"]["fitted"][0] for r in mine)
            a = statistics.mean(r["values"][ANISO][0] for r in mine)
            wins = sorted({r["mip"] for r in mine if r["values"][ANISO][0] < r["values"]["fitted"][0]})
            chosen += [r["values"][ANISO if a < f else "fitted"][0] for r in mine]
            better += a < f
            print(f"| {name} | {f:.4f} | {a:.4f} | {a / f:.3f} | {','.join(map(str, wins)) or '-'} |")
        print(f"\nanisotropic better over all its cases on {better} of {len(maps)} maps; the better per map: "
              f"mean rel. L1 {statistics.mean(chosen):.4f} against fitted's "
              f"{statistics.mean(r['values']['fitted'][0] for r in rows):.4f}")
    if args.json_out:
        with open(args.json_out, "w") as f:
            json.dump({"rows": rows, "summary": summary}, f, indent=1)


if __name__ == "__main__":
    main()
