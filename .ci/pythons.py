"""Run the test suite on every CPython it finds among the versions asked (``make test``).

    python .ci/pythons.py --main-venv .venv --versions "3.10 3.11 3.12 3.13" [-- PYTEST ARGS]

The main venv (the one that lints and builds the docs) runs the whole suite at full size
(``GCU_TEST_SIZE=full``): every test but the ``alone`` ones in parallel (pytest-xdist,
``--jobs`` workers), then the ``alone`` ones one at a time. Every other version found runs the
fast tier (``-m fast``: sans-I/O, in-memory, virtual time; tests/_tiers.py) in parallel in its
own venv, ``.venv-3.X`` (created, or refreshed when pyproject.toml or the package version
changed), at reduced size (``GCU_TEST_SIZE=reduced``, see tests/_scale.py). An interpreter is
looked for in pyenv's versions (``pyenv root``, else ``$PYENV_ROOT`` or ``.pyenv`` in the home
directory), then as ``python3.X`` on PATH. At the end it prints which versions ran (which tier,
how they did) and which were missing. Exit status: 0 if every run passed, 1 if one failed, 2 on
a usage error.

Standard library only: it runs before any venv exists but the main one.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
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
    seconds: float = 0.0
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


def phases(run: Run, jobs: int) -> list[tuple[str, list[str]]]:
    """The pytest invocations of a run: (name, arguments before the user's)."""
    parallel = ["-n", str(jobs)] if jobs > 1 else ["-p", "no:xdist"]
    if run.tier == "full":
        return [("parallel", [*parallel, "-m", "not alone"]),
                ("alone", ["-p", "no:xdist", "-m", "alone"])]  # fmt: skip
    return [("fast tier", [*parallel, "-m", "fast"])]


def run_suite(run: Run, pytest_args: list[str], jobs: int) -> None:
    assert run.venv is not None
    env = {**os.environ, "GCU_TEST_SIZE": run.size}
    start = time.monotonic()
    failed = []
    for name, args in phases(run, jobs):
        print(f"\n=== Python {run.version} ({run.venv.name}, {run.size} size, {run.tier} "
              f"tier): {name} ===", flush=True)  # fmt: skip
        proc = subprocess.run(
            [str(run.venv / "bin" / "python"), "-m", "pytest", *args, *pytest_args],
            cwd=ROOT, env=env, check=False)  # fmt: skip
        if proc.returncode not in (0, NO_TESTS):
            failed.append(f"{name}: pytest exit {proc.returncode}")
    run.seconds = time.monotonic() - start
    run.status = "passed" if not failed else f"FAILED ({'; '.join(failed)})"


def summary(runs: list[Run]) -> str:
    lines = ["", "=== Python versions ==="]
    for run in runs:
        if run.status == "missing":
            lines.append(f"  {run.version:<6} missing: {run.detail}")
        else:
            minutes, seconds = divmod(round(run.seconds), 60)
            lines.append(f"  {run.version:<6} ran {run.detail}, {run.size} size, {run.tier} "
                         f"tier: {run.status} in {minutes}m{seconds:02d}s")  # fmt: skip
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
    runs = [Run(main_minor, main_venv / "bin" / "python", main_venv, "full", "full", "pending",
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
        run_suite(run, args.pytest_args, args.jobs)
    print(summary(runs), flush=True)
    return 0 if all(r.status in ("passed", "missing") for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
