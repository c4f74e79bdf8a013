"""ROSS side by side with modaltol on Friswell et al. (2010) Example 5.9.1.

ROSS's `rotor_example()` is the same rotor as `examples/friswell_5_9_1.toml` (six Timoshenko
elements, two disks, bearings of 1 MN/m). This prints its six lowest natural frequencies at 0
and 4000 rpm, the time of its first modal point (imports and set-up excluded), of a warm one
(best of 20), and of a 20-speed sweep (the cost of a Campbell diagram, per speed), then runs
`modaltol modal` on the example at the same speeds and prints its frequencies and its time per
point from `modaltol sweep` (the process's total, parse and recording included, divided by
the number of speeds).

Outside the test suite: ROSS needs Python >= 3.13.

    python3.13 -m venv /tmp/rossv && /tmp/rossv/bin/pip install ross-rotordynamics
    cargo build --release
    /tmp/rossv/bin/python benches/ross_friswell.py [target/release/modaltol]

With `--mesh n …` it prints instead ROSS's warm modal point (best of 7, 4000 rpm) of the same
rotor meshed into n elements (n a multiple of 6, the disks on nodes n/3 and 2n/3), the rotor
`cargo run --release --example scale_shaft -- n` times in modaltol.
"""

import json
import subprocess
import sys
import time

import numpy as np
import ross as rs

ARGS = sys.argv[1:]
MODALTOL = ARGS[0] if ARGS and ARGS[0] != "--mesh" else "target/release/modaltol"
EXAMPLE = "examples/friswell_5_9_1.toml"
SPEEDS = [0.0, 4000 * np.pi / 30]


def best(f, rounds):
    out = float("inf")
    for _ in range(rounds):
        t = time.perf_counter()
        f()
        out = min(out, time.perf_counter() - t)
    return out


def friswell_5_9_1(elements=6):
    """Example 5.9.1 built in ROSS as the book gives it (ROSS's `rotor_example()` is another
    rotor): six elements of 0.25 m, Ø 50 mm, steel; disks on nodes 2 and 4; bearings of 1 MN/m
    on nodes 0 and 6. `elements` (a multiple of 6) meshes the same shaft finer."""
    n = elements
    steel = rs.Material(name="Steel_5_9_1", rho=7810, E=211e9, G_s=81.2e9)
    shaft = [
        rs.ShaftElement(L=1.5 / n, idl=0.0, odl=0.05, material=steel, shear_effects=True,
                        rotary_inertia=True, gyroscopic=True)
        for _ in range(n)
    ]
    disks = [
        rs.DiskElement.from_geometry(n=n // 3, material=steel, width=0.07, i_d=0.05, o_d=0.28),
        rs.DiskElement.from_geometry(n=2 * n // 3, material=steel, width=0.07, i_d=0.05,
                                     o_d=0.35),
    ]
    bearings = [rs.BearingElement(n=k, kxx=1e6, kyy=1e6, cxx=0) for k in (0, n)]
    return rs.Rotor(shaft, disks, bearings)


def mesh(sizes) -> None:
    speed = SPEEDS[1]
    for n in sizes:
        rotor = friswell_5_9_1(n)
        rotor.run_modal(speed=speed)
        calls = iter(speed * (1 - 1e-6 * np.arange(1, 100)))
        warm = best(lambda: rotor.run_modal(speed=next(calls)), 7)
        wd = rotor.run_modal(speed=speed).wd[:6]
        print(f"ROSS, {n} elements: warm modal point {1e3 * warm:.2f} ms, wd =", np.round(wd, 2))


def ross() -> None:
    rotor = friswell_5_9_1()
    t = time.perf_counter()
    modal = rotor.run_modal(speed=SPEEDS[1])
    first = time.perf_counter() - t
    for speed in SPEEDS:
        modal = rotor.run_modal(speed=speed)
        print(f"ROSS {rs.__version__} at {speed:.2f} rad/s: wd =", np.round(modal.wd[:6], 2))
    # A new speed each call (ROSS keeps the last results of a speed asked for again).
    calls = iter(SPEEDS[1] * (1 - 1e-6 * np.arange(1, 1000)))
    warm = best(lambda: rotor.run_modal(speed=next(calls)), 20)
    sweep = np.linspace(0, SPEEDS[1], 20)
    shifts = iter(np.arange(1, 100))
    campbell = best(lambda: rotor.run_campbell(sweep * (1 - 1e-7 * next(shifts))), 3) / len(sweep)
    print(
        f"ROSS: first modal point {1e3 * first:.1f} ms, warm {1e3 * warm:.2f} ms (best of 20), "
        f"Campbell {1e3 * campbell:.2f} ms a speed (20 speeds, best of 3)"
    )


def modaltol() -> None:
    for speed in SPEEDS:
        out = subprocess.run(
            [MODALTOL, "modal", EXAMPLE, "--speed", str(speed), "--format", "json"],
            capture_output=True,
            check=True,
            text=True,
        ).stdout
        wd = sorted(m["damped_frequency"] for m in json.loads(out)["modes"])
        wd = [w for w in wd if w > 10][:6]
        print(f"modaltol at {speed:.2f} rad/s: wd =", np.round(wd, 2))
    one = best(
        lambda: subprocess.run(
            [MODALTOL, "modal", EXAMPLE, "--speed", str(SPEEDS[1])],
            capture_output=True,
            check=True,
        ),
        10,
    )
    speeds = f"0:{SPEEDS[1] + 1e-6:.9f}:{SPEEDS[1] / 19:.12f}"
    csv = subprocess.run(
        [MODALTOL, "sweep", EXAMPLE, "--speed", speeds], capture_output=True, check=True,
        text=True,
    ).stdout.splitlines()
    count = len({line.split(",")[0] for line in csv[1:]})
    sweep = best(
        lambda: subprocess.run(
            [MODALTOL, "sweep", EXAMPLE, "--speed", speeds],
            capture_output=True,
            check=True,
        ),
        5,
    )
    print(
        f"modaltol: one modal point {1e3 * one:.1f} ms (the whole process, best of 10), "
        f"sweep {1e3 * sweep / count:.2f} ms a speed ({count} speeds, the whole process, "
        "best of 5)"
    )


if __name__ == "__main__":
    if "--mesh" in sys.argv:
        mesh([int(a) for a in sys.argv[sys.argv.index("--mesh") + 1:]])
    else:
        ross()
        modaltol()
