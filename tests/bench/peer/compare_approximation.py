#!/usr/bin/env python3
"""Cost of rkhs-study against the machine and against scikit-learn, as ratios, in one run.

Prints, for a build tree (default build/release):
  1. the dense kernels' speed (bench/bench_dense): the DGEMM probe of this processor and the
     power-function phase of a 2-D Matern 5/2 trial (both triangular solves per point) in
     GFLOP/s and as a fraction of the probe;
  2. the 2-D trial of tests/bench/peer/matern_2d_peer.toml (Matern nu = 5/2, length scale 0.2,
     n grid centres on the unit square, 16384 evaluation points; power_function_sup, sup_error,
     l2_error) with rkhs-study on one and on two threads (wall time, peak memory), and with
     scikit-learn's GaussianProcessRegressor on one thread (fit + predict(return_std=True)) when
     SciPy and scikit-learn are importable (approx_gp_peer.py; NumPy on OpenBLAS with
     OPENBLAS_CORETYPE and OPENBLAS_L2_SIZE unset for that command, README.md of this folder),
     checking that the two tools' metrics agree to 1e-8 relative;
  3. the wall time of shipped studies on one thread (--studies).

Nothing here is part of CTest or CI: timings belong to an otherwise idle machine.

  tests/bench/peer/compare_approximation.py [--build build/release] [--n 4096]
      [--studies gram_and_power,iso8608] [--peer-root /opt/pyref/root]
"""
import argparse
import csv
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
SOURCE = HERE.parents[2]


def timed(command, env=None, cwd=None):
    """Runs command under /usr/bin/time -v: (wall seconds, peak resident MB, stdout+stderr)."""
    start = time.monotonic()
    result = subprocess.run(["/usr/bin/time", "-v", *command], capture_output=True, text=True,
                            env=env, cwd=cwd, check=False)
    wall = time.monotonic() - start
    output = result.stdout + result.stderr
    if result.returncode != 0:
        raise SystemExit(f"failed ({result.returncode}): {' '.join(command)}\n{output[-2000:]}")
    peak = re.search(r"Maximum resident set size \(kbytes\): (\d+)", output)
    return wall, (int(peak.group(1)) / 1024 if peak else float("nan")), output


def dense_speed(build):
    bench = build / "bench" / "bench_dense"
    if not bench.exists():
        return None
    result = subprocess.run([str(bench), "--benchmark_filter=power_function_phase/64",
                             "--benchmark_format=csv"], capture_output=True, text=True, check=True)
    rows = list(csv.DictReader(line for line in result.stdout.splitlines() if "," in line))
    return rows


def trial_study(n, folder):
    text = (HERE / "matern_2d_peer.toml").read_text()
    text = re.sub(r"^n = \[\d+\]", f"n = [{n}]", text, flags=re.M)
    path = folder / f"matern_2d_peer_n{n}.toml"
    path.write_text(text)
    return path


def rkhs_trial(exe, study, threads, out):
    wall, peak, _ = timed([str(exe), "run", str(study), "--threads", str(threads), "--no-store",
                           "--no-plots", "--quiet", "--out", str(out)])
    with open(out / "trials.csv", newline="") as handle:
        row = next(csv.DictReader(handle))
    return wall, peak, row


def sklearn_trial(study, n, trials_csv, peer_root):
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE")}
    env.update(PYTHONPATH=str(peer_root / "usr/lib/python3/dist-packages"),
               LD_LIBRARY_PATH=str(peer_root / "usr/lib/x86_64-linux-gnu"),
               OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    probe = subprocess.run(["/usr/bin/python3", "-c", "import sklearn, scipy"], env=env,
                           capture_output=True, check=False)
    if probe.returncode != 0:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "peer.csv"
        wall, peak, output = timed(["/usr/bin/python3", str(HERE / "approx_gp_peer.py"), str(study),
                                    "--n", str(n), "--threads", "1", "--out", str(out),
                                    "--rkhs-trials", str(trials_csv)], env=env)
        with open(out, newline="") as handle:
            row = next(csv.DictReader(handle))
    return wall, peak, row, output


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default=str(SOURCE / "build" / "release"))
    parser.add_argument("--n", default="4096", help="comma-separated n (squares)")
    parser.add_argument("--studies", default="gram_and_power,iso8608")
    parser.add_argument("--peer-root", default="/opt/pyref/root")
    args = parser.parse_args()
    build = pathlib.Path(args.build)
    exe = build / "rkhs-study"

    print("## Dense kernels (one thread)")
    rows = dense_speed(build)
    if rows:
        for row in rows:
            label = row.get("label", "")
            print(f"- {row['name']} [{label}]: {float(row['GFLOP/s']) / 1e9:.1f} GFLOP/s"
                  + (f", {float(row['of_dgemm']):.0%} of the DGEMM probe "
                     f"({float(row['dgemm_GFLOP/s']):.1f} GFLOP/s)" if row.get("of_dgemm") else ""))
    else:
        print("- bench/bench_dense not built")

    print("\n## The 2-D trial (Matern 5/2, l = 0.2, 16384 points)")
    print("| n | rkhs-study 1 thread | rkhs-study 2 threads | speed-up | scikit-learn 1 thread |"
          " rkhs-study / scikit-learn | peak MB (rkhs 1 thr / sklearn) | max rel. difference |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp)
        for n in [int(v) for v in args.n.split(",")]:
            study = trial_study(n, folder)
            one, peak_one, row = rkhs_trial(exe, study, 1, folder / f"one_{n}")
            two, _, _ = rkhs_trial(exe, study, 2, folder / f"two_{n}")
            peer = sklearn_trial(study, n, folder / f"one_{n}" / "trials.csv",
                                 pathlib.Path(args.peer_root))
            if peer is None:
                print(f"| {n} | {one:.2f} s | {two:.2f} s | {one / two:.2f}x | not importable | | "
                      f"{peak_one:.0f} / | |")
                continue
            wall, peak, peer_row, _ = peer
            seconds = float(peer_row["fit_seconds_min"]) + float(peer_row["predict_seconds_min"])
            worst = max(abs(float(peer_row[m]) - float(row[m])) / abs(float(row[m]))
                        for m in ("power_function_sup", "sup_error", "l2_error"))
            print(f"| {n} | {one:.2f} s | {two:.2f} s | {one / two:.2f}x | {seconds:.2f} s "
                  f"(fit + predict; process {wall:.2f} s) | {one / seconds:.2f} | {peak_one:.0f} / "
                  f"{peak:.0f} | {worst:.1e}{'' if worst <= 1e-8 else ' (above 1e-8!)'} |")

    print("\n## Shipped studies (one thread, no store, no plots)")
    for name in [s for s in args.studies.split(",") if s]:
        with tempfile.TemporaryDirectory() as tmp:
            wall, peak, _ = timed([str(exe), "run", str(SOURCE / "studies" / f"{name}.toml"),
                                   "--threads", "1", "--no-store", "--no-plots", "--quiet",
                                   "--out", tmp], cwd=SOURCE)
        print(f"- {name}: {wall:.2f} s, peak {peak:.0f} MB")


if __name__ == "__main__":
    main()
