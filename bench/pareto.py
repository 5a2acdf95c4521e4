#!/usr/bin/env python3
"""Usage: bench/pareto.py TABLE.json OUTDIR

Frame time against relative RMSE for every way in a `scatterd bench --calibrate` table, one plot
per terms (OUTDIR/pareto-<terms>.png, gnuplot) and a Markdown table on stdout with each scene's
Pareto front marked."""
import json
import os
import subprocess
import sys
import tempfile

table = json.load(open(sys.argv[1]))
outdir = sys.argv[2]
by_terms = {}
for e in table["entries"]:
    by_terms.setdefault(e["class"]["terms"], []).append(e)
for terms, entries in sorted(by_terms.items()):
    print(f"\n{terms} terms ({table['width']} x {table['height']}); * marks the Pareto front\n")
    print("| scene | way | frame | rel. RMSE |")
    print("| --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        plots = []
        for e in entries:
            rows = sorted((e["ms"][w], err, w) for w, err in e["error"].items() if w in e["ms"])
            best = 1e9
            for ms, err, w in rows:
                front = err < best
                best = min(best, err)
                print(f"| {e['scene']} | {w}{' *' if front else ''} | {ms:.0f} ms | {100 * err:.2f} % |")
            path = os.path.join(tmp, e["scene"] + ".dat")
            with open(path, "w") as f:
                for ms, err, w in rows:
                    f.write(f"{ms} {err} {w}\n")
            plots.append(f"'{path}' using 1:2 with points pt 7 title '{e['scene']}'")
        png = os.path.join(outdir, f"pareto-{terms}.png")
        script = f"""set terminal pngcairo size 900,600 noenhanced
set output '{png}'
set logscale xy
set xlabel 'frame time (ms), {table['width']} x {table['height']}'
set ylabel 'relative RMSE against the reference ({terms} terms)'
set grid
set key outside right
plot {', '.join(plots)}
"""
        subprocess.run(["gnuplot"], input=script.encode(), check=True)
