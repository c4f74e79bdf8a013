"""ROSS side by side with modaltol on the unbalance response: Friswell et al. (2010) Example
5.9.1's rotor (as `ross_bearings.py` builds it, in both tools) on damped bearings, stiffer in x
than in y and coupled (symmetrically: `ross_bearings.py`'s case A is unstable at rest, and an
unstable rotor has no steady response), with an unbalance of 1e-4 kg·m at disk 1 (node 2,
phase 0).

ROSS's `run_unbalance_response` and `modaltol sweep --transfer input=u,output=PORT` over the
same speeds (0 to 1000 rad/s, step 0.5), read at both disks in both lateral directions (ROSS's
x and y are modaltol's global y and z: the shaft runs along x). For every response it prints
the largest relative difference of the amplitude over the speeds and each tool's peaks (local
maxima above 1 % of the largest), refined by a parabola through the log-amplitude at the
three speeds around the grid's maximum, with their relative differences.

Then the peaks as modaltol locates them between the speeds of a coarse grid (`modaltol analyze
--no-quadrature --no-monte-carlo --speed 0:1000:25`, `peaks.csv`: Newton on the exact
derivative in speed) against ROSS's, refined on a fine grid about each (step 0.002 rad/s over
±1 rad/s, then the parabola).

Outside the test suite: ROSS needs Python >= 3.13.

    python3.13 -m venv /tmp/rossv && /tmp/rossv/bin/pip install ross-rotordynamics
    cargo build --release
    /tmp/rossv/bin/python benches/ross_unbalance.py [target/release/modaltol]
"""

import csv
import io
import os
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ross_bearings  # noqa: E402

# The bearings (N/m, N·s/m), in place of case A's.
ross_bearings.CONST.update(
    kxx=1e6, kyy=0.8e6, kxy=2e4, kyx=2e4, cxx=2000.0, cyy=1500.0, cxy=100.0, cyx=100.0
)

EXE = sys.argv[1] if len(sys.argv) > 1 else "target/release/modaltol"
STEP = 0.5
SPEEDS = np.arange(0.0, 1000.0 + STEP / 2, STEP)
UNBALANCE = 1e-4
# (ROSS node, ROSS direction, modaltol node frame, direction, port name)
PROBES = [
    (2, 0, "shaft_2_frame", [0, 1, 0], "n2_x"),
    (2, 1, "shaft_2_frame", [0, 0, 1], "n2_y"),
    (4, 0, "shaft_4_frame", [0, 1, 0], "n4_x"),
    (4, 1, "shaft_4_frame", [0, 0, 1], "n4_y"),
]


def with_unbalance(text):
    x = {"shaft_2_frame": 0.5, "shaft_4_frame": 1.0}
    for _, _, body, direction, name in PROBES:
        text += f"""
[[ports]]
name = "{name}"
type = "translation"
body = "{body}"
point = [{x[body]}, 0, 0]
direction = {direction}
"""
    return text + f"""
[[unbalances]]
name = "u"
body = "shaft_2"
point = [0.5, 0, 0]
magnitude = {UNBALANCE}
phase = 0
"""


def peaks(amplitude):
    """Local maxima above 1 % of the largest, refined by a parabola in log-amplitude."""
    a = np.log(amplitude[1:])
    s = SPEEDS[1:]
    out = []
    top = a.max()
    for i in range(1, len(a) - 1):
        if a[i] >= a[i - 1] and a[i] > a[i + 1] and a[i] > top + np.log(0.01):
            d = (a[i + 1] - a[i - 1]) / 2 / (2 * a[i] - a[i - 1] - a[i + 1])
            out.append((s[i] + d * STEP, np.exp(a[i] - (a[i + 1] - a[i - 1]) * d / 4)))
    return out


def fine_peak(rotor, speed):
    """ROSS's peak near `speed`, on a grid of step 0.002 rad/s over ±1 rad/s: (speed, amplitude)
    per probe."""
    step = 0.002
    speeds = np.arange(speed - 1.0, speed + 1.0 + step / 2, step)
    resp = rotor.run_unbalance_response(node=2, unbalance_magnitude=UNBALANCE,
                                        unbalance_phase=0.0, speed_range=speeds)
    out = {}
    for node, direction, _, _, name in PROBES:
        a = np.log(np.abs(resp.forced_resp[6 * node + direction, :]))
        i = int(np.argmax(a[1:-1])) + 1
        d = (a[i + 1] - a[i - 1]) / 2 / (2 * a[i] - a[i - 1] - a[i + 1])
        out[name] = (speeds[i] + d * step, np.exp(a[i] - (a[i + 1] - a[i - 1]) * d / 4))
    return out


def located_peaks(path, name, tmp):
    """modaltol's peaks of the response at `name` from a grid of step 25 rad/s: (speed,
    amplitude) per maximum, and the seconds the run took."""
    with open(path) as f:
        text = f.read()
    text = text.replace('transfer = { input = "disk2_y", output = "disk1_y", order = 1 }',
                        f'transfer = {{ input = "u", output = "{name}" }}')
    model = os.path.join(tmp, f"peaks_{name}.toml")
    with open(model, "w") as f:
        f.write(text)
    out = os.path.join(tmp, f"out_{name}")
    t0 = time.perf_counter()
    subprocess.run([EXE, "analyze", model, "--no-quadrature", "--no-monte-carlo",
                    "--speed", "0:1000:25", "--output", out],
                   check=True, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    with open(os.path.join(out, "peaks.csv")) as f:
        rows = list(csv.DictReader(f))
    first = rows[0]["case"] if rows else None
    return [(float(r["speed"]), float(r["magnitude"])) for r in rows
            if r["case"] == first and r["kind"] == "maximum"], seconds


def main():
    rotor = ross_bearings.ross_rotor("A")
    t0 = time.perf_counter()
    ross = rotor.run_unbalance_response(node=2, unbalance_magnitude=UNBALANCE,
                                        unbalance_phase=0.0, speed_range=SPEEDS)
    t_ross = time.perf_counter() - t0
    worst_amp = worst_speed = worst_peak = 0.0
    t_ours = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "unbalance.toml")
        with open(path, "w") as f:
            f.write(with_unbalance(ross_bearings.modaltol_model("A")))
        for node, direction, _, _, name in PROBES:
            theirs = np.abs(ross.forced_resp[6 * node + direction, :])
            t0 = time.perf_counter()
            out = subprocess.run(
                [EXE, "sweep", path, "--speed", f"0:1000:{STEP}",
                 "--transfer", f"input=u,output={name}"],
                check=True, capture_output=True, text=True).stdout
            t_ours += time.perf_counter() - t0
            first = {}
            for row in csv.DictReader(io.StringIO(out)):
                first.setdefault(float(row["speed"]), float(row["transfer_magnitude"]))
            ours = np.array([first[s] for s in SPEEDS])
            rel = np.abs(ours[1:] - theirs[1:]) / theirs[1:]
            worst_amp = max(worst_amp, rel.max())
            print(f"{name}: largest relative difference of the amplitude {rel.max():.1e}")
            for (sr, ar), (so, ao) in zip(peaks(theirs), peaks(ours)):
                ds, da = abs(so - sr) / sr, abs(ao - ar) / ar
                worst_speed, worst_peak = max(worst_speed, ds), max(worst_peak, da)
                print(f"  peak: ROSS {ar:.6e} m at {sr:.3f} rad/s | modaltol {ao:.6e} m at "
                      f"{so:.3f} rad/s  (speed {ds:.1e}, amplitude {da:.1e})")
        print(f"largest relative difference: amplitude {worst_amp:.1e}, peak amplitude "
              f"{worst_peak:.1e}, peak speed {worst_speed:.1e}")
        # The peaks located between the speeds of a coarse grid against ROSS's, refined.
        fine = {}
        worst = [0.0, 0.0]
        t_located = 0.0
        for node, direction, _, _, name in PROBES:
            ours, seconds = located_peaks(path, name, tmp)
            t_located += seconds
            theirs = np.abs(ross.forced_resp[6 * node + direction, :])
            for (sr, _) in peaks(theirs):
                key = round(sr, 1)
                if key not in fine:
                    fine[key] = fine_peak(rotor, sr)
                rs, ra = fine[key][name]
                so, ao = min(ours, key=lambda x: abs(x[0] - rs))
                ds, da = abs(so - rs) / rs, abs(ao - ra) / ra
                worst = [max(worst[0], ds), max(worst[1], da)]
                print(f"  {name} located: modaltol {ao:.6e} m at {so:.4f} rad/s | ROSS (fine) "
                      f"{ra:.6e} m at {rs:.4f} rad/s  (speed {ds:.1e}, amplitude {da:.1e})")
        print(f"located peaks (grid of 25 rad/s) against ROSS's refined: speed {worst[0]:.1e}, "
              f"amplitude {worst[1]:.1e}; modaltol {t_located:.1f} s for four analyses")
    print(f"time: ROSS {t_ross:.1f} s for the response at {len(SPEEDS)} speeds (every dof); "
          f"modaltol {t_ours:.1f} s for four sweeps (each: equilibrium, modes, whirl, |H|)")


if __name__ == "__main__":
    main()
