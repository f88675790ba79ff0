"""Run the test suite on every CPython it finds among the versions asked (``make test``).

    python .ci/pythons.py --main-venv .venv --versions "3.10 3.11 3.12 3.13" [-- PYTEST ARGS]

The main venv (the one that lints and builds the docs) runs every test at full size
(``GCU_TEST_SIZE=full``): the full tier (every kind but ``fast``; tests/helpers/tiers.py) and the
``heavy`` fast tests in parallel (pytest-xdist, ``--jobs`` workers) in the background, while the
rest of the fast tier (sans-I/O, in-memory, virtual time) runs in one process, then every other
version found runs the fast tier in its own venv, ``.venv-3.X`` (created, or refreshed when
pyproject.toml or the package version changed), at reduced size (``GCU_TEST_SIZE=reduced``, see
tests/helpers/scale.py); last, with nothing else running, the ``alone`` tests one at a time.
An interpreter is looked for in pyenv's versions (``pyenv root``, else ``$PYENV_ROOT`` or
``.pyenv`` in the home directory), then as ``python3.X`` on PATH. At the end it prints which
versions ran (which tier, how they did) and which were missing. Exit status: 0 if every run
passed, 1 if one failed, 2 on a usage error.

Standard library only: it runs before any venv exists but the main one.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STAMP = ".installed-stamp"
INPUTS = ("pyproject.toml", "src/gcu_async/__init__.py")
"""What a venv's install depends on: it is redone when one is newer than the stamp."""


@dataclass
class Run:
    version: str
    python: Path | None = None
    venv: Path | None = None
    size: str = "reduced"
    tier: str = "fast"
    status: str = "missing"
    timing: str = ""
    detail: str = ""


def version_of(python: Path | str) -> str | None:
    """``"3.12.1"`` for a working interpreter, None if it does not run (a pyenv shim for a
    version that is not installed, say)."""
    try:
        out = subprocess.run(
            [str(python), "-c", "import sys; print('%d.%d.%d' % sys.version_info[:3])"],
            capture_output=True, text=True, timeout=30, check=True,
        ).stdout.strip()  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    return out if re.fullmatch(r"\d+\.\d+\.\d+", out) else None


def pyenv_roots() -> list[Path]:
    roots: list[Path] = []
    pyenv = shutil.which("pyenv")
    if pyenv is not None:
        try:
            out = subprocess.run([pyenv, "root"], capture_output=True, text=True, timeout=30,
                                 check=True).stdout.strip()  # fmt: skip
            if out:
                roots.append(Path(out))
        except (OSError, subprocess.SubprocessError):
            pass
    if os.environ.get("PYENV_ROOT"):
        roots.append(Path(os.environ["PYENV_ROOT"]))
    roots.append(Path.home() / ".pyenv")
    return list(dict.fromkeys(roots))


def _patch_key(path: Path) -> tuple[int, ...]:
    return tuple(int(n) for n in re.findall(r"\d+", path.name))


def find_python(version: str, roots: list[Path]) -> Path | None:
    """A CPython ``version`` (``"3.12"``): the newest patch release under a pyenv root,
    else ``python3.12`` on PATH; it must run and report that version."""
    candidates: list[Path] = []
    for root in roots:
        found = [d for d in (root / "versions").glob(f"{version}.*")
                 if re.fullmatch(rf"{re.escape(version)}\.\d+", d.name)]  # fmt: skip
        for d in sorted(found, key=_patch_key, reverse=True):
            candidates.append(d / "bin" / f"python{version}")
    on_path = shutil.which(f"python{version}")
    if on_path is not None:
        candidates.append(Path(on_path))
    for python in candidates:
        actual = version_of(python) if python.exists() else None
        if actual is not None and actual.rsplit(".", 1)[0] == version:
            return python
    return None


def needs_install(venv: Path) -> bool:
    stamp = venv / STAMP
    if not stamp.exists() or not (venv / "bin" / "python").exists():
        return True
    return any((ROOT / name).stat().st_mtime > stamp.stat().st_mtime for name in INPUTS)


def install(python: Path, venv: Path, extras: str, groups: str) -> None:
    print(f"--- creating {venv.name} with {python}", flush=True)
    subprocess.run([str(python), "-m", "venv", str(venv)], check=True)
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet"]
    subprocess.run([*pip, "--upgrade", "pip"], check=True)  # --group needs pip >= 25.1
    target = f".[{extras}]" if extras else "."
    group_args = [arg for group in groups.split(",") if group for arg in ("--group", group)]
    subprocess.run([*pip, "-e", target, *group_args], check=True, cwd=ROOT)
    (venv / STAMP).touch()


NO_TESTS = 5
"""pytest's exit status when the selection is empty (no ``alone`` tests, say): not a failure."""


@dataclass
class Phase:
    """One pytest invocation of a run. ``lane``: "background" phases start first and run
    while the "foreground" ones (every run's, one after another) do; "last" ones run alone
    once both are done."""

    run: Run
    name: str
    args: list[str]
    lane: str
    failed: str = ""
    seconds: float = 0.0


def phases(run: Run, jobs: int) -> list[Phase]:
    """The pytest invocations of a run. The full tier is mostly real-time waiting: it runs in
    parallel (``jobs`` pytest-xdist workers) in the background with the ``heavy`` fast tests,
    while the rest of the fast tier, CPU-bound and ~10,000 small tests (pytest-xdist's per-test
    cost would exceed the gain), runs in one process in the foreground, this run's then the
    other interpreters'. The other interpreters' runs are at reduced size, where nothing is
    heavy: they run the whole fast tier."""
    serial = ["-p", "no:xdist"]
    parallel = ["-n", str(jobs)] if jobs > 1 else serial
    if run.tier == "every":
        return [Phase(run, "full tier", [*parallel, "-m", "(not fast or heavy) and not alone"],
                      "background"),
                Phase(run, "fast tier", [*serial, "-m", "fast and not heavy"], "foreground"),
                Phase(run, "alone", [*serial, "-m", "alone"], "last")]  # fmt: skip
    return [Phase(run, "fast tier", [*serial, "-m", "fast"], "foreground")]


def _command(phase: Phase, pytest_args: list[str]) -> list[str]:
    assert phase.run.venv is not None
    return [str(phase.run.venv / "bin" / "python"), "-m", "pytest", *phase.args, *pytest_args]


def _heading(phase: Phase) -> str:
    run = phase.run
    assert run.venv is not None
    return (f"\n=== Python {run.version} ({run.venv.name}, {run.size} size): {phase.name} ===")


def _finish(phase: Phase, returncode: int, start: float) -> None:
    phase.seconds = time.monotonic() - start
    if returncode not in (0, NO_TESTS):
        phase.failed = f"{phase.name}: pytest exit {returncode}"


def run_phases(all_phases: list[Phase], pytest_args: list[str]) -> None:
    """Background phases (output to a file, printed when they end), the foreground ones in
    turn, then the last ones."""
    env = dict(os.environ)
    background = []
    for phase in (p for p in all_phases if p.lane == "background"):
        log = tempfile.TemporaryFile(mode="w+")  # noqa: SIM115 - closed below
        print(f"{_heading(phase)} (started; its output follows when it ends)", flush=True)
        proc = subprocess.Popen(_command(phase, pytest_args), cwd=ROOT, stdout=log,
                                stderr=subprocess.STDOUT, text=True,
                                env={**env, "GCU_TEST_SIZE": phase.run.size})  # fmt: skip
        background.append((phase, proc, log, time.monotonic()))
    for lane in ("foreground", "last"):
        for phase in (p for p in all_phases if p.lane == lane):
            print(_heading(phase), flush=True)
            start = time.monotonic()
            proc = subprocess.run(_command(phase, pytest_args), cwd=ROOT, check=False,
                                  env={**env, "GCU_TEST_SIZE": phase.run.size})  # fmt: skip
            _finish(phase, proc.returncode, start)
        if lane == "foreground":
            for phase, bproc, log, start in background:
                returncode = bproc.wait()
                _finish(phase, returncode, start)
                log.seek(0)
                print(_heading(phase), flush=True)
                print(log.read(), end="", flush=True)
                log.close()
    for run in {id(p.run): p.run for p in all_phases}.values():
        mine = [p for p in all_phases if p.run is run]
        failed = [p.failed for p in mine if p.failed]
        run.status = "passed" if not failed else f"FAILED ({'; '.join(failed)})"
        run.timing = ", ".join(f"{p.name} {_minutes(p.seconds)}" for p in mine)


def _minutes(seconds: float) -> str:
    minutes, rest = divmod(round(seconds), 60)
    return f"{minutes}m{rest:02d}s"


def summary(runs: list[Run]) -> str:
    lines = ["", "=== Python versions ==="]
    for run in runs:
        if run.status == "missing":
            lines.append(f"  {run.version:<6} missing: {run.detail}")
        else:
            lines.append(f"  {run.version:<6} ran {run.detail}, {run.size} size, {run.tier} "
                         f"tier: {run.status} ({run.timing})")  # fmt: skip
    ran = [r.version for r in runs if r.status != "missing"]
    missing = [r.version for r in runs if r.status == "missing"]
    lines.append(f"  ran: {', '.join(ran) or 'none'}; missing: {', '.join(missing) or 'none'}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--main-venv", type=Path, required=True,
                        help="venv that runs the full-size suite (and already exists)")
    parser.add_argument("--versions", default="3.10 3.11 3.12 3.13",
                        help="CPython minor versions to look for, space-separated")
    parser.add_argument("--extras", default="mavlink,web,capture",
                        help="extras installed in the other versions' venvs")
    parser.add_argument("--groups", default="test",
                        help="dependency groups (pyproject.toml) installed in the other "
                        "versions' venvs, comma-separated")
    parser.add_argument("--jobs", type=int, default=4,
                        help="pytest-xdist workers per run (1: no xdist)")
    parser.add_argument("--venv-prefix", default=".venv-",
                        help="the other versions' venvs are PREFIX3.X (default .venv-)")
    parser.add_argument("pytest_args", nargs="*", help="arguments for pytest (after --)")
    args = parser.parse_args(argv)  # fmt: skip
    versions = args.versions.split()
    if any(not re.fullmatch(r"3\.\d+", v) for v in versions):
        parser.error(f"--versions: {args.versions!r} is not a list like '3.10 3.11'")
    main_venv = args.main_venv if args.main_venv.is_absolute() else ROOT / args.main_venv
    main_full = version_of(main_venv / "bin" / "python")
    if main_full is None:
        parser.error(f"--main-venv: {main_venv} has no working bin/python")
    main_minor = main_full.rsplit(".", 1)[0]

    if args.jobs < 1:
        parser.error(f"--jobs: {args.jobs} is not a number of workers >= 1")
    runs = [Run(main_minor, main_venv / "bin" / "python", main_venv, "full", "every", "pending",
                detail=f"CPython {main_full} (main venv {main_venv.name})")]  # fmt: skip
    roots = pyenv_roots()
    for version in versions:
        if version == main_minor:
            continue
        python = find_python(version, roots)
        if python is None:
            looked = ", ".join(str(r / "versions") for r in roots)
            runs.append(Run(version, detail=f"no CPython {version} in {looked} or on PATH"))
            continue
        run = Run(version, python, ROOT / f"{args.venv_prefix}{version}", "reduced", "fast",
                  "pending", detail=f"CPython {version_of(python)} ({python})")  # fmt: skip
        runs.append(run)
    print("Python versions: " + ", ".join(
        f"{r.version} ({r.size} size, {r.tier} tier)" if r.status != "missing"
        else f"{r.version} (missing)" for r in runs), flush=True)  # fmt: skip

    ready = []
    for run in runs:
        if run.status == "missing":
            continue
        assert run.venv is not None
        assert run.python is not None
        if run.size != "full" and needs_install(run.venv):
            try:
                install(run.python, run.venv, args.extras, args.groups)
            except subprocess.CalledProcessError as exc:
                run.status = f"FAILED (venv set-up: {exc})"
                continue
        ready.append(run)
    start = time.monotonic()
    run_phases([phase for run in ready for phase in phases(run, args.jobs)], args.pytest_args)
    print(summary(runs), flush=True)
    print(f"  tests took {_minutes(time.monotonic() - start)} in all", flush=True)
    return 0 if all(r.status in ("passed", "missing") for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
