"""The cost of a stochastic Campbell diagram: ROSS's `ST_Rotor` (plain Monte Carlo over rebuilt
rotors) against modaltol's quadrature, for the same rotor and the same tolerances.

The rotor is Friswell et al. (2010) Example 5.9.1 (`examples/friswell_5_9_1.toml`) with its
tolerances, each a normal variable with ±3σ the tolerance: shaft diameter 0.2 %, E 2 %, ρ 1 %,
each disk's mass 2 % (its inertias scale with it), the bearings' stiffness 10 % (both bearings,
both directions, one variable). ROSS: `ST_Rotor` of N rotors (`ST_ShaftElement` with random
outer diameter and material, `ST_DiskElement` with random m, Id, Ip, `ST_BearingElement` with
random kxx = kyy) and `run_campbell` at the speeds. modaltol: `analyze --no-monte-carlo` at the
same speeds (the quadrature, and the Taylor methods beside it). Both report σ of every lateral
mode's ω_d at every speed. ROSS's `run_campbell` keeps each rotor's frequencies in its own
order, so where modes cross (the third pair's backward mode and the axial mode near 650 rad/s)
one index holds different modes in different rotors; the script prints σ both ways: of ROSS's
index whose mean is nearest the modaltol mode's, and of each rotor's frequency nearest that
mean (matched per sample; in a group of modes closer than 6σ, as a split pair, each rotor's as
many frequencies nearest the group's centre, in order of value), which it compares. Left out: the axial mode
(ROSS's bearings have no axial stiffness, the example's do) and the modes within 30 rad/s of it,
which cross it in some rotors. Printed: wall times, the largest difference of σ relative to ROSS's own sampling error
(σ/√(2N)), and how many samples a Monte Carlo would need for a σ as precise as the
quadrature's own error estimate (`std_error`).

Outside the test suite: ROSS needs Python >= 3.13.

    python3.13 -m venv /tmp/rossv && /tmp/rossv/bin/pip install ross-rotordynamics
    cargo build --release
    /tmp/rossv/bin/python benches/ross_stochastic.py [target/release/modaltol] [N]
"""

import csv
import os
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore")
import ross as rs  # noqa: E402
import ross.stochastic as srs  # noqa: E402

EXE = sys.argv[1] if len(sys.argv) > 1 else "target/release/modaltol"
N = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE = os.path.join(HERE, "..", "examples", "friswell_5_9_1.toml")
SPEEDS = np.arange(0.0, 420.0 + 1, 60.0)
FREQUENCIES = 8
NOMINAL = dict(d=0.05, E=211e9, rho=7810.0, disk1=32.5897, disk2=51.5253, k=1e6)
TOLERANCE = dict(d=0.002, E=0.02, rho=0.01, disk1=0.02, disk2=0.02, k=0.10)
WIDTH, BORE, D1, D2 = 0.07, 0.05, 0.28, 0.35


def samples(rng):
    return {k: v * (1 + TOLERANCE[k] / 3 * rng.standard_normal(N)) for k, v in NOMINAL.items()}


def disk(n, m, outer):
    ip = m * (outer**2 + BORE**2) / 8
    i_d = m * (outer**2 + BORE**2) / 16 + m * WIDTH**2 / 12
    return srs.ST_DiskElement(n=n, m=m, Id=i_d, Ip=ip, is_random=["m", "Id", "Ip"])


def st_rotor(s):
    materials = [rs.Material(name=f"steel_{i}", rho=s["rho"][i], E=s["E"][i], G_s=81.2e9)
                 for i in range(N)]
    shaft = [
        srs.ST_ShaftElement(L=0.25, idl=0.0, odl=s["d"], material=materials,
                            shear_effects=True, rotary_inertia=True, gyroscopic=True,
                            is_random=["odl", "material"])
        for _ in range(6)
    ]
    disks = [disk(2, s["disk1"], D1), disk(4, s["disk2"], D2)]
    bearings = [srs.ST_BearingElement(n=n, kxx=s["k"], kyy=s["k"], cxx=0.0,
                                      is_random=["kxx", "kyy"]) for n in (0, 6)]
    return srs.ST_Rotor(shaft, disks, bearings)


def main():
    rng = np.random.default_rng(1)
    t0 = time.perf_counter()
    rotors = st_rotor(samples(rng))
    camp = rotors.run_campbell(SPEEDS, frequencies=FREQUENCIES)
    t_ross = time.perf_counter() - t0
    wd = camp.wd  # (frequencies, speeds, N)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run([EXE, "analyze", EXAMPLE, "--speed", "0:420:60", "--no-monte-carlo",
                        "--output", tmp], check=True, capture_output=True)
        t_ours = time.perf_counter() - t0
        with open(os.path.join(tmp, "tolerance.csv")) as f:
            rows = [r for r in csv.DictReader(f)
                    if r["quantity"] == "damped_frequency" and r["method"] == "quadrature"
                    and r["mean"]]
    worst = 0.0
    needed = []
    print(f"{'speed':>8} {'modaltol':>9} {'σ':>8} | {'ROSS σ, its order':>17} {'matched':>8} "
          f"{'diff/se':>7}")
    for i, w in enumerate(SPEEDS):
        here = sorted((r for r in rows if abs(float(r["speed"]) - w) < 1e-6),
                      key=lambda r: float(r["mean"]))
        kept = []
        for r in here:
            mean, ours = float(r["mean"]), float(r["std"])
            if mean > 1000 or mean < 10 or abs(mean - 650.41) < 0.5:
                continue  # above ROSS's frequencies, the twist on its soft coupling (ROSS's
                # shaft is free), the axial mode (ROSS's bearings have no axial stiffness)
            if abs(mean - 650.7) < 30:
                print(f"{w:8.2f} {mean:9.3f} {ours:8.4f} | crosses ROSS's axial mode: left out")
                continue
            kept.append((mean, ours, r))
        # Groups of modes closer than 6σ (a split pair); in each rotor, the group's as many
        # frequencies nearest its centre, in order of value.
        groups = []
        for m in kept:
            if groups and m[0] - groups[-1][-1][0] < 6 * max(m[1], groups[-1][-1][1]):
                groups[-1].append(m)
            else:
                groups.append([m])
        x = wd[:, i, :]
        for g in groups:
            centre = np.mean([m[0] for m in g])
            near = np.sort(np.argsort(np.abs(x - centre), axis=0)[: len(g), :], axis=0)
            picked = np.sort(np.take_along_axis(x, near, axis=0), axis=0)
            for rank, (mean, ours, r) in enumerate(g):
                # ROSS's own order: the frequency index whose mean is nearest.
                j = min(range(FREQUENCIES), key=lambda j: abs(wd[j, i, :].mean() - mean))
                sorted_sd = wd[j, i, :].std(ddof=1)
                sd = picked[rank, :].std(ddof=1)
                z = abs(ours - sd) / (sd / np.sqrt(2 * (N - 1)))
                worst = max(worst, z)
                if r.get("std_error"):
                    # Samples for a Monte Carlo σ as precise as the quadrature's error estimate.
                    needed.append(ours**2 / (2 * float(r["std_error"]) ** 2))
                print(f"{w:8.2f} {mean:9.3f} {ours:8.4f} | {sorted_sd:17.4f} {sd:8.4f} {z:7.2f}")
    print(f"largest |σ difference| (ROSS matched per sample) over ROSS's standard error of σ: "
          f"{worst:.2f}")
    if needed:
        print(f"samples a Monte Carlo needs for a σ as precise as the quadrature's error "
              f"estimate: {min(needed):.3g} at the least, median {np.median(needed):.3g}")
    print(f"time: ROSS ST_Rotor.run_campbell, {N} rotors x {len(SPEEDS)} speeds: {t_ross:.1f} s; "
          f"modaltol analyze --no-monte-carlo (quadrature and Taylor methods, "
          f"{len(SPEEDS)} speeds): {t_ours:.1f} s")


if __name__ == "__main__":
    main()
