#!/usr/bin/env python3
"""Side by side: rkhs-study and the SciPy Radau peer on the same adaptive trials.

For each trial selector, writes a study file holding only that trial (the original study's
settings, one kernel, one law, one n, the chosen integrator), runs

    rkhs-study run TRIAL.toml --out DIR --threads 1 --quiet --no-plots --no-store

in a temporary directory (no result store is read or written, so nothing is reused from an
earlier run), reads trials.csv (steps, L2 error) and summary.json (the trial's seconds), then runs
adaptive_radau_peer.py on the same study file, one after the other on one thread each, and
prints one Markdown table:

    trial | peer steps | peer s | rkhs-study steps | rkhs-study s | step ratio | speed-up |
    peer L2 | rkhs-study L2 | L2 rel. diff

step ratio = peer steps / rkhs-study steps, speed-up = peer seconds / rkhs-study seconds (the
trial's time in both: set-up, integration and measurement; the peer's integration alone is in
the CSV written with --csv).

A trial selector is KERNEL[:key=value,...]/LAW/N, e.g. "gaussian:sigma=1/rkhs/10" or
"bspline:degree=2/rkhs/100"; a selector that matches several kernel entries (say "bspline/rkhs/100"
with degree = [1, 2]) stands for each of them.

The driver itself needs only the Python standard library (3.11, tomllib); the peer needs NumPy
and SciPy (README.md in this folder: SciPy is never a dependency of the project).

Examples:
    compare_adaptive.py studies/paper_synthetic.toml "gaussian/rkhs/10" "bspline:degree=1/rkhs/100"
    compare_adaptive.py studies/paper_synthetic.toml "gaussian/rkhs/100" --integrator rodas4
    compare_adaptive.py STUDY "gaussian/rkhs/10" --integrator radau5 --integrator rodas4:restart_at_kinks=false
"""
import argparse
import csv
import itertools
import json
import math
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib

HERE = pathlib.Path(__file__).resolve().parent
REPOSITORY = HERE.parents[2]
PEER = HERE / "adaptive_radau_peer.py"
METRICS = ["l2_error", "sup_error", "interpolant_l2_error", "gap_to_projection",
           "final_state_error", "steps", "rejected_steps", "segments", "rhs_evaluations",
           "jacobian_evaluations"]


# ---------------------------------------------------------------------------------------------
# A small TOML writer (strings, booleans, numbers, arrays, inline tables), enough for studies.


def toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {value!r} as TOML")


def toml_document(document):
    lines = []
    for key, value in document.items():
        if isinstance(value, dict):
            lines.append(f"[{key}]")
            lines += [f"{k} = {toml_value(v)}" for k, v in value.items()]
            lines.append("")
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for table in value:
                lines.append(f"[[{key}]]")
                lines += [f"{k} = {toml_value(v)}" for k, v in table.items()]
                lines.append("")
        else:
            raise TypeError(f"top-level key {key!r} is not a table")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Trials


def as_list(value):
    return value if isinstance(value, list) else [value]


def expand_entry(entry):
    """A plugin entry with list-valued parameters as axes: one entry per combination."""
    keys = [k for k in entry if k not in ("name", "tier")]
    combos = itertools.product(*(as_list(entry[k]) for k in keys))
    return [{"name": entry["name"], **dict(zip(keys, values))} for values in combos]


def value_matches(actual, wanted):
    try:
        return float(actual) == float(wanted)
    except (TypeError, ValueError):
        return str(actual).lower() == str(wanted).lower()


def parse_selector(text):
    try:
        kernel, law, n = text.split("/")
        name, _, rest = kernel.partition(":")
        params = {}
        for item in filter(None, rest.split(",")):
            key, _, value = item.partition("=")
            params[key.strip()] = value.strip()
        return name.strip(), params, law.strip(), int(n)
    except ValueError:
        raise SystemExit(f"bad trial selector {text!r}: expected KERNEL[:key=value,...]/LAW/N")


def kernel_text(entry):
    params = ", ".join(f"{k}={v}" for k, v in entry.items() if k != "name")
    return f"{entry['name']} ({params})" if params else entry["name"]


def parse_literal(text):
    """KEY=VALUE's value as a TOML literal (number, boolean, quoted string), else a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def trial_studies(study, selectors, integrators, laps):
    """(label, study document) for each trial the selectors name."""
    kernels = [e for entry in study.get("kernel", []) for e in expand_entry(entry)]
    laws = [e for entry in study.get("law", [{"name": "rkhs"}]) for e in expand_entry(entry)]
    out = []
    for selector in selectors:
        name, params, law_name, n = parse_selector(selector)
        chosen_kernels = [k for k in kernels if k["name"] == name and all(
            key in k and value_matches(k[key], value) for key, value in params.items())]
        chosen_laws = [law for law in laws if law["name"] == law_name]
        if not chosen_kernels or not chosen_laws:
            raise SystemExit(f"trial selector {selector!r} matches no kernel/law of the study")
        for kernel, law in itertools.product(chosen_kernels, chosen_laws):
            document = {}
            header = dict(study.get("study", {}))
            header["name"] = f"peer_comparison_{len(out) + 1}"
            header["metrics"] = METRICS
            document["study"] = header
            for table in ("domain", "adaptive", "solver", "limits"):
                if table in study:
                    document[table] = dict(study[table])
            document["grid"] = {"n": [n]}
            document["kernel"] = [kernel]
            for table in ("target", "plant", "centres"):
                if table in study:
                    document[table] = study[table]
            document["law"] = [law]
            document["integrator"] = [integrators[0]]
            document.setdefault("adaptive", {})
            if laps is not None:
                document["adaptive"]["laps"] = laps
                document["adaptive"].pop("final_time", None)
            document.setdefault("limits", {})["trial_seconds"] = 0
            several_gains = sum(1 for other in laws if other["name"] == law_name) > 1
            label = f"{kernel_text(kernel)}, {law_name}" + (
                f" (Gamma = {law.get('gamma', 1e-3):g})" if several_gains else "") + f", n = {n}"
            out.append((label, document))
    return out


# ---------------------------------------------------------------------------------------------
# Running


def run_rkhs_study(executable, study_file, work, extra):
    work.mkdir(parents=True, exist_ok=True)
    out_dir = work / "out"
    command = [str(executable), "run", str(study_file), "--out", str(out_dir), "--threads", "1",
               "--quiet", "--no-plots", "--no-store"] + extra
    started = time.perf_counter()
    done = subprocess.run(command, cwd=work, capture_output=True, text=True)
    wall = time.perf_counter() - started
    note = ""
    if done.returncode == 0:
        with open(out_dir / "trials.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        with open(out_dir / "summary.json") as f:
            summary = json.load(f)
        seconds = float(summary["trials"][0]["seconds"]) if summary["trials"] else math.nan
        provenance = summary["provenance"]
    else:
        # The run died after its trial (a crash while writing outputs, say): the journal, written
        # as each trial ends, still has the metrics, but not the trial's own time.
        journal = out_dir / "journal.csv"
        rows = list(csv.DictReader(open(journal, newline=""))) if journal.exists() else []
        if not rows:
            raise SystemExit(f"rkhs-study failed ({done.returncode}):\n{done.stdout}{done.stderr}")
        print(f"warning: rkhs-study exited with status {done.returncode}; metrics from "
              f"journal.csv, time = the whole process's wall time", file=sys.stderr)
        seconds, provenance, note = wall, {"version": "?", "git_commit": "?"}, "process"
    if len(rows) != 1:
        raise SystemExit(f"{study_file}: expected one trial, rkhs-study ran {len(rows)}")
    row = rows[0]
    if row["status"] != "ok":
        raise SystemExit(f"{study_file}: rkhs-study trial failed: {row['reason']}")
    return {"steps": int(float(row["steps"])), "rejected_steps": int(float(row["rejected_steps"])),
            "segments": int(float(row["segments"])),
            "rhs_evaluations": int(float(row["rhs_evaluations"])),
            "jacobian_evaluations": int(float(row["jacobian_evaluations"])),
            "l2_error": float(row["l2_error"]), "sup_error": float(row["sup_error"]),
            "interpolant_l2_error": float(row["interpolant_l2_error"]),
            "final_state_error": float(row["final_state_error"]),
            "solve": row.get("solve", ""), "seconds": seconds, "run_seconds": wall,
            "time_note": note, "version": provenance["version"],
            "commit": provenance["git_commit"]}


def run_peer(python, study_file, work, environment, extra):
    out_csv = work / "peer.csv"
    command = [python, str(PEER), str(study_file), "--out", str(out_csv), "--quiet"] + extra
    done = subprocess.run(command, cwd=work, capture_output=True, text=True, env=environment)
    if done.returncode != 0:
        raise SystemExit(f"the peer failed ({done.returncode}):\n{done.stdout}{done.stderr}")
    with open(out_csv, newline="") as f:
        rows = list(csv.DictReader(f))
    if len(rows) != 1:
        raise SystemExit(f"{study_file}: expected one trial, the peer ran {len(rows)}")
    row = rows[0]
    return {"steps": int(row["steps"]), "rejected_steps": int(row["rejected_steps"]),
            "segments": int(row["segments"]), "nfev": int(row["nfev"]), "njev": int(row["njev"]),
            "nlu": int(row["nlu"]), "l2_error": float(row["l2_error"]),
            "sup_error": float(row["sup_error"]),
            "interpolant_l2_error": float(row["interpolant_l2_error"]),
            "final_state_error": float(row["final_state_error"]), "solve": row["solve"],
            "seconds": float(row["seconds"]), "integration_seconds": float(row["integration_seconds"]),
            "scipy": row["scipy"]}


def relative_difference(a, b):
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def default_executable():
    if os.environ.get("RKHS_STUDY"):
        return os.environ["RKHS_STUDY"]
    roots = [REPOSITORY]
    try:  # a linked worktree without a build of its own: the main worktree's build
        common = subprocess.run(["git", "-C", str(REPOSITORY), "rev-parse", "--git-common-dir"],
                                capture_output=True, text=True, check=True).stdout.strip()
        roots.append((REPOSITORY / common).resolve().parent)
    except (OSError, subprocess.CalledProcessError):
        pass
    for root in roots:
        for preset in ("release", "relwithdebinfo", "debug"):
            candidate = root / "build" / preset / "rkhs-study"
            if candidate.exists():
                return str(candidate)
    return shutil.which("rkhs-study") or "rkhs-study"


def main():
    parser = argparse.ArgumentParser(
        description="rkhs-study against the SciPy Radau peer on the same adaptive trials",
        epilog="Trial selectors: KERNEL[:key=value,...]/LAW/N, e.g. gaussian:sigma=1/rkhs/10.")
    parser.add_argument("study", help="an adaptive study file")
    parser.add_argument("trials", nargs="+", help="trial selectors")
    parser.add_argument("--integrator", action="append", default=[],
                        metavar="NAME[:KEY=VALUE,...]",
                        help="rkhs-study integrator, with parameters after a colon (repeatable: "
                             "each is run on every trial; default: the study's first)")
    parser.add_argument("--integrator-param", action="append", default=[], metavar="KEY=VALUE",
                        help="a parameter of every rkhs-study integrator (repeatable)")
    parser.add_argument("--rtol", type=float, help="rtol for both (default: the study's)")
    parser.add_argument("--atol", type=float, help="atol for both (default: the study's)")
    parser.add_argument("--laps", type=float, help="laps for both (default: the study's)")
    parser.add_argument("--rkhs-study", default=default_executable(),
                        help="the rkhs-study executable (default: $RKHS_STUDY, else "
                             "build/<preset>/rkhs-study of this repository or of its main "
                             "worktree, else PATH)")
    parser.add_argument("--rkhs-study-arg", action="append", default=[], metavar="ARG",
                        help="an extra argument for rkhs-study run (repeatable, e.g. --plugin=X.so)")
    parser.add_argument("--python", default="/usr/bin/python3" if os.path.exists("/usr/bin/python3")
                        else sys.executable, help="Python for the peer (with NumPy)")
    parser.add_argument("--scipy-root", default=os.environ.get("RKHS_PEER_SCIPY_ROOT"),
                        help="a directory with an unpacked python3-scipy (and liblbfgsb0) .deb "
                             "(README.md); default $RKHS_PEER_SCIPY_ROOT, else SciPy from the "
                             "environment")
    parser.add_argument("--peer-restart-at-kinks", action="store_true",
                        help="let the peer restart at kinks of phi(s(t)) as rkhs-study does")
    parser.add_argument("--cpu", type=int, help="pin both programs to this core")
    parser.add_argument("--csv", help="also write every measured column to this CSV file")
    parser.add_argument("--keep", help="keep the trial studies and outputs in this directory")
    args = parser.parse_args()

    if args.cpu is not None:
        os.sched_setaffinity(0, {args.cpu})
    with open(args.study, "rb") as f:
        study = tomllib.load(f)
    if study.get("study", {}).get("kind") != "adaptive":
        raise SystemExit(f"{args.study} is not an adaptive study")
    original = dict(study.get("integrator", [{"name": "rosenbrock4"}])[0])
    integrators = []
    for text in args.integrator or [original["name"]]:
        name, _, rest = text.partition(":")
        integrator = dict(original) if name == original["name"] else {
            "name": name, "rtol": original.get("rtol", 1e-6), "atol": original.get("atol", 1e-8)}
        for item in list(filter(None, rest.split(","))) + args.integrator_param:
            key, sep, value = item.partition("=")
            if not sep:
                raise SystemExit(f"integrator parameter {item!r}: expected KEY=VALUE")
            integrator[key.strip()] = parse_literal(value.strip())
        if args.rtol is not None:
            integrator["rtol"] = args.rtol
        if args.atol is not None:
            integrator["atol"] = args.atol
        integrator.setdefault("rtol", 1e-6)
        integrator.setdefault("atol", 1e-8)
        integrators.append(integrator)
    if len({(i["rtol"], i["atol"]) for i in integrators}) > 1:
        raise SystemExit("the integrators have different rtol/atol; the peer uses one pair")

    environment = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    if args.scipy_root:
        root = pathlib.Path(args.scipy_root)
        packages = root / "usr/lib/python3/dist-packages"
        libraries = root / "usr/lib/x86_64-linux-gnu"
        environment["PYTHONPATH"] = os.pathsep.join(
            filter(None, [str(packages), environment.get("PYTHONPATH")]))
        environment["LD_LIBRARY_PATH"] = os.pathsep.join(
            filter(None, [str(libraries), environment.get("LD_LIBRARY_PATH")]))
    peer_extra = ["--restart-at-kinks"] if args.peer_restart_at_kinks else []

    trials = trial_studies(study, args.trials, integrators, args.laps)
    base = pathlib.Path(args.keep) if args.keep else pathlib.Path(tempfile.mkdtemp(prefix="peer-"))
    base.mkdir(parents=True, exist_ok=True)
    results = []
    try:
        for index, (label, document) in enumerate(trials, start=1):
            work = (base / f"trial-{index}").resolve()
            work.mkdir(parents=True, exist_ok=True)
            ours = []
            for k, integrator in enumerate(integrators):
                document["integrator"] = [integrator]
                study_file = work / f"trial-{integrator['name']}-{k + 1}.toml"
                study_file.write_text(f"# {label}: one trial of {args.study}, written by "
                                      f"compare_adaptive.py\n" + toml_document(document))
                print(f"[{index}/{len(trials)}] {label}: rkhs-study {integrator['name']} ...",
                      file=sys.stderr, flush=True)
                ours.append(run_rkhs_study(args.rkhs_study, study_file,
                                           work / f"{integrator['name']}-{k + 1}",
                                           args.rkhs_study_arg))
            print(f"[{index}/{len(trials)}] {label}: peer ...", file=sys.stderr, flush=True)
            peer = run_peer(args.python, study_file, work, environment, peer_extra)
            results.append((label, peer, ours))
    finally:
        if not args.keep:
            shutil.rmtree(base, ignore_errors=True)

    def describe(integrator):
        parameters = ", ".join(f"{k} = {toml_value(v)}" for k, v in integrator.items()
                               if k != "name")
        return f"`{integrator['name']}` ({parameters})"

    known = [o for _, _, ours in results for o in ours if o["version"] != "?"]
    version = f"{known[0]['version']} ({known[0]['commit']})" if known else "(version unknown)"
    scipy_version = results[0][1]["scipy"] if results else "?"
    print(f"Study `{args.study}`; rkhs-study {version} with "
          f"{'; '.join(describe(i) for i in integrators)}; SciPy {scipy_version} "
          f"`solve_ivp(method=\"Radau\")` with the exact Jacobian, same rtol/atol; one thread "
          f"each, run one after the other.\n")
    def short(integrator):  # the name and the parameters that are not the tolerances
        extra = [f"{k}={toml_value(v)}" for k, v in integrator.items()
                 if k not in ("name", "rtol", "atol")]
        return integrator["name"] + (f" ({', '.join(extra)})" if extra else "")

    several = len(integrators) > 1
    print("| trial |" + (" integrator |" if several else "") + " peer steps | peer s | "
          "rkhs-study steps | rkhs-study s | step ratio | speed-up | peer L2 | rkhs-study L2 | "
          "L2 rel. diff |")
    print("|---|" + ("---|" if several else "") + "---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    processes = False
    for label, peer, ours in results:
        for integrator, o in zip(integrators, ours):
            mark = "*" if o["time_note"] else ""
            processes |= bool(mark)
            print(f"| {label} |" + (f" {short(integrator)} |" if several else "") +
                  f" {peer['steps']:,} | {peer['seconds']:.2f} | {o['steps']:,} | "
                  f"{o['seconds']:.2f}{mark} | {peer['steps'] / o['steps']:.2f} | "
                  f"{peer['seconds'] / o['seconds']:.1f}x | {peer['l2_error']:.6e} | "
                  f"{o['l2_error']:.6e} | "
                  f"{relative_difference(peer['l2_error'], o['l2_error']):.1e} |")
    # The interpolant's L2 error checks kernel, centres and Gram solve apart from the
    # integration; values near round-off (below 1e-9) are compared absolutely.
    pairs = [(p["interpolant_l2_error"], o["interpolant_l2_error"])
             for _, p, ours in results for o in ours]
    resolved = [relative_difference(a, b) for a, b in pairs if min(a, b) > 1e-9]
    unresolved = [abs(a - b) for a, b in pairs if min(a, b) <= 1e-9]
    static = f"largest relative difference {max(resolved):.1e}" if resolved else ""
    if unresolved:
        static += ("; " if static else "") + (f"largest absolute difference {max(unresolved):.1e} "
                                             f"where it is at round-off level")
    print("\nstep ratio = peer steps / rkhs-study steps; speed-up = peer seconds / rkhs-study "
          "seconds (the whole trial in both). Static check of kernel, centres and Gram solve, the "
          f"interpolant's L2 error: {static or '-'}.")
    if processes:
        print("* rkhs-study did not finish its run normally: metrics from journal.csv, time of "
              "the whole process.")

    if args.csv and results:
        peer_keys, our_keys = list(results[0][1]), list(results[0][2][0])
        with open(args.csv, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(["trial", "integrator"] + [f"peer_{k}" for k in peer_keys] +
                            [f"rkhs_study_{k}" for k in our_keys])
            for label, peer, ours in results:
                for integrator, o in zip(integrators, ours):
                    writer.writerow([label, short(integrator)] + [peer[k] for k in peer_keys] +
                                    [o[k] for k in our_keys])

if __name__ == "__main__":
    main()
