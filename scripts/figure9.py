#!/usr/bin/python3
"""Zhao, Li & Barbic 2016, Figure 9: async (stable and paper coupling) against
Schroeder et al. 2011 on the dragon, with the jaw pulled down (models/dragon/figure9.json).

Runs offlineSimulator on derived scenes written into --out, extracts the jaw tip and the
jaw hinge opening per frame with `afsimTool csv`, compares each run with a converged
single-rate backward Euler reference, prints a Markdown table and writes a frame sheet
(frameRenderer frames assembled with matplotlib).

    /usr/bin/python3 scripts/figure9.py --bin build/bin --out /tmp/figure9

Measured quantities (0-based vertex ids of models/dragon/dragon.veg):
  jaw tip       vertex 1125, the jaw vertex farthest from the head centre (0.93, 1.05, 0)
  hinge opening distance between jaw vertex 1112 (0.987, 0.962, -0.073) and head vertex
                713 (0.913, 1.038, -0.063): the closest pair of a jaw-only and a head-only
                vertex at the back of the jaw (one element layer across the interface)
Displacements are the linear FEM ones (no warping); warping is applied only when drawing.
"""

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(REPO, "models", "dragon", "figure9.json")
TIP = 1125
HINGE_JAW, HINGE_HEAD = 1112, 713
SHEET_FRAMES = [2, 5, 8, 11, 17, 29]  # 0-based frame records, t = (k + 1) / 30
REF_STEPS_PER_LARGE_STEP = 150  # reference h = hL / 150 = hS (about 90 s on 2 cores)


def configurations(scene):
    h_large = scene["integrator"]["timestep"]

    def derived(name, options, timestep=h_large):
        return {"integrator": name, "options": options, "timestep": timestep}

    regions = scene["integrator"]["options"]["regions"]
    return [
        ("reference", "backward Euler, h = hL/%d" % REF_STEPS_PER_LARGE_STEP,
         derived("backward-euler", {}, h_large / REF_STEPS_PER_LARGE_STEP)),
        ("async-stable", "async, stable coupling, m = 150",
         derived("async", {"regions": regions, "coupling": "stable", "schur": "low-rank"})),
        ("async-paper", "async, paper coupling, m = 150",
         derived("async", {"regions": regions, "coupling": "paper", "schur": "low-rank"})),
        ("schroeder2011", "schroeder2011, m = 150",
         derived("schroeder2011", {"regions": regions})),
        ("schroeder2011-hL8", "schroeder2011, m = 150, hL/8",
         derived("schroeder2011", {"regions": regions}, h_large / 8)),
    ]


def write_scene(scene, cfg, path):
    s = json.loads(json.dumps(scene))
    s["mesh"]["file"] = os.path.join(os.path.dirname(SCENE), scene["mesh"]["file"])
    s["integrator"] = {"name": cfg["integrator"], "timestep": cfg["timestep"],
                       "options": cfg["options"]}
    with open(path, "w") as f:
        json.dump(s, f, indent=1)


def run_simulation(binary, scene_path, afsim, log):
    start = time.time()
    proc = subprocess.run([os.path.join(binary, "offlineSimulator"), scene_path,
                           "--output", afsim], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
    elapsed = time.time() - start
    with open(log, "w") as f:
        f.write(proc.stdout + proc.stderr)
    summary = re.search(r"\(\d+ per frame\), ([0-9.]+) s", proc.stdout)
    return {"rc": proc.returncode,
            "wall": float(summary.group(1)) if summary else None,
            "process_wall": elapsed,
            "messages": [l for l in proc.stderr.splitlines() if "ETA" not in l]}


def read_positions(binary, afsim, out_csv):
    if not os.path.exists(afsim) or os.path.getsize(afsim) == 0:
        return None
    ids = [TIP, HINGE_JAW, HINGE_HEAD]
    proc = subprocess.run([os.path.join(binary, "afsimTool"), "csv", afsim, "--vertices",
                           ",".join(map(str, ids)), "--scene", SCENE, "-o", out_csv],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        return None
    rows = list(csv.DictReader(open(out_csv)))
    if not rows:
        return None
    t = np.array([float(r["time"]) for r in rows])
    u = {v: np.array([[float(r["u%d_%s" % (v, c)]) for c in "xyz"] for r in rows]) for v in ids}
    p = {v: np.array([[float(r["p%d_%s" % (v, c)]) for c in "xyz"] for r in rows]) for v in ids}
    opening = np.linalg.norm(p[HINGE_JAW] - p[HINGE_HEAD], axis=1)
    rest = np.linalg.norm((p[HINGE_JAW] - u[HINGE_JAW]) - (p[HINGE_HEAD] - u[HINGE_HEAD]), axis=1)
    return {"t": t, "tip": u[TIP], "opening": opening - rest[0], "rest": rest[0]}


def render(binary, scene_path, afsim, folder):
    frames = [f for f in SHEET_FRAMES]
    os.makedirs(folder, exist_ok=True)
    for f in frames:
        subprocess.run([os.path.join(binary, "frameRenderer"), afsim, "--scene", scene_path,
                        "-o", folder, "--frames", "%d:%d:1" % (f, f + 1), "--width", "360",
                        "--height", "300", "--warp", "rotation-strain", "--tint-set", "jaw",
                        "--ground", "--camera-position", "1.75", "1.15", "1.45",
                        "--camera-target", "0.95", "0.95", "0.0", "--fov", "28", "--quiet"],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(REPO, "build", "bin"))
    ap.add_argument("--out", required=True)
    ap.add_argument("--sheet", default=None, help="frame sheet PNG (default OUT/figure9.png)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    scene = json.load(open(SCENE))
    frame_count = scene["frames"]["count"]
    results = []
    for key, label, cfg in configurations(scene):
        scene_path = os.path.join(args.out, key + ".json")
        afsim = os.path.join(args.out, key + ".afsim")
        write_scene(scene, cfg, scene_path)
        print("running %s (h = %.6g s) ..." % (label, cfg["timestep"]), file=sys.stderr, flush=True)
        run = run_simulation(args.bin, scene_path, afsim, os.path.join(args.out, key + ".log"))
        data = read_positions(args.bin, afsim, os.path.join(args.out, key + ".csv"))
        frames_done = 0 if data is None else len(data["t"])
        print("  rc %d, %d frames, %.1f s" % (run["rc"], frames_done, run["process_wall"]),
              file=sys.stderr, flush=True)
        for m in run["messages"]:
            print("  " + m, file=sys.stderr)
        results.append({"key": key, "label": label, "cfg": cfg, "scene": scene_path,
                        "afsim": afsim, "run": run, "data": data, "frames": frames_done})

    ref = results[0]["data"]
    if ref is None or len(ref["t"]) < frame_count:
        sys.exit("figure9: the reference did not complete")
    amplitude = np.max(np.linalg.norm(ref["tip"], axis=1))
    ref_open_amp = np.max(np.abs(ref["opening"]))

    per_frame = [["frame", "time"] + ["%s_tip_err" % r["key"] for r in results[1:]] +
                 ["%s_opening" % r["key"] for r in results]]
    for k in range(frame_count):
        row = [k, ref["t"][k]]
        for r in results[1:]:
            d = r["data"]
            row.append(np.linalg.norm(d["tip"][k] - ref["tip"][k]) / amplitude
                       if d is not None and k < len(d["t"]) else "")
        for r in results:
            d = r["data"]
            row.append(d["opening"][k] if d is not None and k < len(d["t"]) else "")
        per_frame.append(row)
    with open(os.path.join(args.out, "errors.csv"), "w", newline="") as f:
        csv.writer(f).writerows(per_frame)

    print("Reference: %s, h = %.4g s; jaw-tip (vertex %d) motion amplitude max_t |u| = %.4g m;"
          " hinge (vertices %d-%d) rest distance %.4g m, opening (distance - rest) between"
          " %.2f and %.2f mm." %
          (results[0]["label"], results[0]["cfg"]["timestep"], TIP, amplitude, HINGE_JAW,
           HINGE_HEAD, ref["rest"], 1e3 * ref["opening"].min(), 1e3 * ref["opening"].max()))
    print()
    print("| configuration | h (s) | max tip error / amplitude | final tip error / amplitude |"
          " max hinge-opening error (mm) | max hinge-opening error / ref. max opening |"
          " max hinge opening (mm) |"
          " wall time (s) | status |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in results:
        d = r["data"]
        wall = ("%.1f" % r["run"]["wall"]) if r["run"]["wall"] is not None else \
            "%.1f (process)" % r["run"]["process_wall"]
        if r["frames"] >= frame_count and r["run"]["rc"] == 0:
            status = "completed (%d frames)" % r["frames"]
        else:
            status = "failed at frame %d (%d frames kept)" % (r["frames"], r["frames"])
        if r is results[0]:
            print("| %s | %.4g | 0 | 0 | 0 | 0 | %.2f | %s | %s |" %
                  (r["label"], r["cfg"]["timestep"], 1e3 * np.max(np.abs(d["opening"])),
                   wall, status))
            continue
        n = min(r["frames"], frame_count)
        if n == 0:
            print("| %s | %.4g | - | - | - | - | - | %s | %s |" %
                  (r["label"], r["cfg"]["timestep"], wall, status))
            continue
        tip_err = np.linalg.norm(d["tip"][:n] - ref["tip"][:n], axis=1) / amplitude
        open_err = np.abs(d["opening"][:n] - ref["opening"][:n])
        rel_open = np.max(open_err) / ref_open_amp
        print("| %s | %.4g | %.3f | %.3f | %.3f | %.3f | %.2f | %s | %s |" %
              (r["label"], r["cfg"]["timestep"], tip_err.max(), tip_err[-1],
               1e3 * open_err.max(), rel_open, 1e3 * np.max(np.abs(d["opening"][:n])),
               wall, status))
    print()
    for r in results:
        bad = [m for m in r["run"]["messages"] if "blow-up" in m or "warning" in m
               or "error" in m.lower() or "exceeds" in m]
        for m in bad:
            print("- %s: `%s`" % (r["label"], m))

    # Frame sheet.
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = len(results)
    cols = len(SHEET_FRAMES)
    fig, axes = plt.subplots(rows, cols, figsize=(1.9 * cols, 1.65 * rows), squeeze=False)
    for i, r in enumerate(results):
        folder = os.path.join(args.out, r["key"] + "-frames")
        if r["frames"] > 0:
            render(args.bin, r["scene"], r["afsim"], folder)
        for j, f in enumerate(SHEET_FRAMES):
            ax = axes[i][j]
            ax.set_xticks([])
            ax.set_yticks([])
            png = os.path.join(folder, "frame_%05d.png" % f)
            if f < r["frames"] and os.path.exists(png):
                ax.imshow(plt.imread(png))
            else:
                ax.set_facecolor("0.85")
                ax.text(0.5, 0.5, "failed at\nframe %d" % r["frames"], ha="center",
                        va="center", transform=ax.transAxes, fontsize=8)
            if i == 0:
                ax.set_title("t = %.2f s" % ((f + 1) / scene["frames"]["rate"]), fontsize=8)
            if j == 0:
                ax.set_ylabel(r["label"].replace(", ", ",\n", 1), fontsize=7)
    fig.suptitle("Dragon, jaw (red) pulled down for 0.3 s; linear FEM, rotation-strain warping",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.97), pad=0.3)
    sheet = args.sheet or os.path.join(args.out, "figure9.png")
    fig.savefig(sheet, dpi=110)
    print("\nframe sheet: %s; per-frame errors: %s" % (sheet, os.path.join(args.out, "errors.csv")))


if __name__ == "__main__":
    main()
