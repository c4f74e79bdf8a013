"""ROSS side by side with modaltol on journal bearings: Friswell et al. (2010) Example 5.9.1's
rotor (`examples/friswell_5_9_1.toml`) on two bearings that are cross-coupled, damped and not
symmetric, (A) constant and (B) tabulated against the speed (interpolated by PCHIP in both).

For each case and speed (0, 100, 250, 418.879 rad/s) it runs ROSS's `run_modal` and
`modaltol modal --format json` on the same rotor (the modaltol model is the example with its
bushings replaced by `bearing` elements, written to a temporary folder), matches every ROSS
lateral mode below 1000 rad/s to modaltol's nearest, and prints both ω_d, ζ and whirl labels,
then the largest differences. ROSS's 650.41 rad/s mode is axial (its bearings have no axial
stiffness; the example's hold the shaft axially) and is left out. At 0 rad/s modaltol gives no
whirl (nothing spins); ROSS labels the orbits there too.

Outside the test suite: ROSS needs Python >= 3.13.

    python3.13 -m venv /tmp/rossv && /tmp/rossv/bin/pip install ross-rotordynamics
    cargo build --release
    /tmp/rossv/bin/python benches/ross_bearings.py [target/release/modaltol]
"""

import json
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np

warnings.filterwarnings("ignore")
import ross as rs  # noqa: E402

EXE = sys.argv[1] if len(sys.argv) > 1 else "target/release/modaltol"
HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE = os.path.join(HERE, "..", "examples", "friswell_5_9_1.toml")
SPEEDS = [0.0, 100.0, 250.0, 418.879]
TABLE_SPEEDS = [0.0, 100.0, 200.0, 300.0, 450.0]
TABLE = {
    "kxx": [1.0e6, 1.1e6, 1.3e6, 1.6e6, 2.2e6],
    "kyy": [0.8e6, 0.85e6, 0.95e6, 1.1e6, 1.4e6],
    "kxy": [0.0, 0.5e5, 1.2e5, 2.0e5, 3.5e5],
    "kyx": [0.0, -0.6e5, -1.4e5, -2.4e5, -4.0e5],
    "cxx": [300.0, 320.0, 350.0, 400.0, 480.0],
    "cyy": [250.0, 260.0, 280.0, 310.0, 360.0],
    "cxy": [0.0, 10.0, 25.0, 40.0, 60.0],
    "cyx": [0.0, -12.0, -30.0, -45.0, -70.0],
}
CONST = dict(kxx=1e6, kyy=0.8e6, kxy=1.5e5, kyx=-2.0e5, cxx=300.0, cyy=250.0, cxy=40.0, cyx=-30.0)


def ross_rotor(case):
    steel = rs.Material(name="steel_f", rho=7810, E=211e9, G_s=81.2e9)
    shaft = [
        rs.ShaftElement(L=0.25, idl=0.0, odl=0.05, material=steel,
                        shear_effects=True, rotary_inertia=True, gyroscopic=True)
        for _ in range(6)
    ]
    disks = [
        rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28),
        rs.DiskElement.from_geometry(n=4, material=steel, width=0.07, i_d=0.05, o_d=0.35),
    ]
    if case == "A":
        bearings = [rs.BearingElement(n=n, **CONST) for n in (0, 6)]
    else:
        table = {k: np.array(v) for k, v in TABLE.items()}
        bearings = [rs.BearingElement(n=n, speed=np.array(TABLE_SPEEDS), **table) for n in (0, 6)]
    return rs.Rotor(shaft, disks, bearings)


def modaltol_model(case):
    """The example with its two bushings replaced by bearings (the shaft runs along x, so a
    bearing's x is the global y and its y the global z: the same handedness as ROSS's x, y
    about its z)."""
    text = open(EXAMPLE).read()
    text = text[: text.index('[[forces]]\nname = "bearing0"')] + text[text.index("[[ports]]"):]
    if case == "A":
        k = [CONST["kxx"], CONST["kxy"], CONST["kyx"], CONST["kyy"]]
        c = [CONST["cxx"], CONST["cxy"], CONST["cyx"], CONST["cyy"]]
    else:
        for name, values in TABLE.items():
            text += f'\n[[tables]]\nname = "{name}"\nx = {TABLE_SPEEDS}\ny = {values}\n'
        k = ['"kxx(speed)"', '"kxy(speed)"', '"kyx(speed)"', '"kyy(speed)"']
        c = ['"cxx(speed)"', '"cxy(speed)"', '"cyx(speed)"', '"cyy(speed)"']
    for name, node, x in (("bearing0", "shaft_0", 0), ("bearing6", "shaft_6", 1.5)):
        text += f"""
[[forces]]
name = "{name}"
type = "bearing"
body1 = "ground"
body2 = "{node}"
point1 = [{x}, 0, 0]
axis = [1, 0, 0]
stiffness = [[{k[0]}, {k[1]}, 0], [{k[2]}, {k[3]}, 0], [0, 0, "k_thrust"]]
damping = [[{c[0]}, {c[1]}, 0], [{c[2]}, {c[3]}, 0], [0, 0, 0]]
"""
    return text


def main():
    worst_w = worst_z = 0.0
    labels = same = 0
    with tempfile.TemporaryDirectory() as tmp:
        for case in ("A", "B"):
            path = os.path.join(tmp, f"{case}.toml")
            with open(path, "w") as f:
                f.write(modaltol_model(case))
            rotor = ross_rotor(case)
            for w in SPEEDS:
                m = rotor.run_modal(speed=w, num_modes=24)
                out = subprocess.run([EXE, "modal", path, "--speed", str(w), "--format", "json"],
                                     check=True, capture_output=True, text=True).stdout
                ours = json.loads(out)["modes"]
                print(f"case {case}, {w} rad/s:  ROSS ω_d, ζ, whirl | modaltol ω_d, ζ, whirl")
                for wd, z, whirl in zip(m.wd, m.damping_ratio, m.whirl_direction()):
                    if wd > 1000 or abs(wd - 650.408) < 0.01:
                        continue
                    o = min(ours, key=lambda x: abs(x["damped_frequency"] - wd))
                    dw = abs(o["damped_frequency"] - wd) / wd
                    dz = abs(o["damping_ratio"] - z)
                    worst_w, worst_z = max(worst_w, dw), max(worst_z, dz)
                    label = o.get("whirl") or "-"
                    if w > 0:
                        labels += 1
                        same += label == whirl.lower()
                    print(f"  {wd:9.3f} {z:+.5f} {whirl.lower():8} | "
                          f"{o['damped_frequency']:9.3f} {o['damping_ratio']:+.5f} {label}")
    print(f"largest relative difference of ω_d {worst_w:.1e}, of ζ {worst_z:.1e}; "
          f"whirl labels the same at {same} of {labels} modes at speed")


if __name__ == "__main__":
    main()
