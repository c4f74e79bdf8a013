#!/usr/bin/env python3
"""A/B wall times of two modaltol binaries on the shipped examples: interleaved rounds (the
order alternates), best of rounds. Usage (from the repository root):
python3 tests/identity/ab_cli.py OLD_BINARY NEW_BINARY [ROUNDS]"""
import subprocess, time, sys, os
A, B = sys.argv[1], sys.argv[2]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 7
os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
cases = [
 ("governor sweep, 5001 speeds", ["sweep","examples/governor.toml","--speed","0:10:0.002"]),
 ("governor sweep --sensitivity, 5001", ["sweep","examples/governor.toml","--speed","0:10:0.002","--sensitivity"]),
 ("pendulum sweep --sensitivity, 5001", ["sweep","examples/rotating_pendulum.toml","--speed","0:10:0.002","--sensitivity"]),
 ("blade sweep --sensitivity, 1001", ["sweep","examples/rotating_blade.toml","--speed","0:20:0.02","--sensitivity"]),
 ("fourbar sweep --sensitivity, 1001", ["sweep","examples/spinning_spatial_fourbar.toml","--speed","0:10:0.01","--sensitivity"]),
 ("pendulum analyze 300 (1 thread)", ["analyze","examples/rotating_pendulum.toml","--samples","300","--threads","1","-o","/tmp/ab-out"]),
]
best = {}
for r in range(rounds):
    for name, args in cases:
        for tag, b in (("old", A), ("new", B)) if r % 2 == 0 else (("new", B), ("old", A)):
            t = time.perf_counter()
            subprocess.run([b] + args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
            dt = time.perf_counter() - t
            k = (name, tag); best[k] = min(best.get(k, 1e9), dt)
print(f"best of {rounds} rounds, interleaved (old = first binary, new = second), wall seconds")
for name, _ in cases:
    o, n = best[(name,"old")], best[(name,"new")]
    print(f"{name:36s} old {o:8.4f}  new {n:8.4f}  new/old {n/o:6.3f}")
