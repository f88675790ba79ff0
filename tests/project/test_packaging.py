"""Packaging facts a user relies on: one version string, the licence the metadata names, and
a lean ``pytest`` extra whose documented set-up really runs the plugin in a fresh project."""

from __future__ import annotations

import importlib.metadata
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

import gcu_async

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")

ROOT = Path(__file__).resolve().parents[2]


def pyproject() -> dict[str, Any]:
    data: dict[str, Any] = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    return data


# -- one version string ---------------------------------------------------------------------


def test_the_version_is_written_once_in_the_package() -> None:
    data = pyproject()
    assert "version" not in data["project"]
    assert "version" in data["project"]["dynamic"]
    assert data["tool"]["hatch"]["version"]["path"] == "src/gcu_async/__init__.py"
    source = (ROOT / "src" / "gcu_async" / "__init__.py").read_text(encoding="utf-8")
    [written] = re.findall(r'^__version__ = "([^"]+)"$', source, re.MULTILINE)
    assert written == gcu_async.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+(?:[abc]\d+|\.dev\d+)?", written)


def test_cli_version_and_installed_metadata_agree_with_the_package() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "gcu_async.cli", "--version"],
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
    )
    assert proc.stdout.strip() == f"gcu-async {gcu_async.__version__}"
    # the installed distribution was built from the same string (reinstall after a bump:
    # `make` does, as pyproject.toml and __init__.py are prerequisites of its venv stamp)
    assert importlib.metadata.version("gcu-async") == gcu_async.__version__


# -- licence --------------------------------------------------------------------------------


def test_license_file_is_the_mit_licence_the_metadata_names() -> None:
    assert pyproject()["project"]["license"] == "MIT"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License\n")
    assert "Copyright (c) 2026 The gcu_async authors" in text
    assert 'THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND' in text
    assert "License-Expression: MIT" in importlib.metadata.metadata("gcu-async").as_string()


# -- the pytest extra -----------------------------------------------------------------------


def _names(requirements: list[str]) -> set[str]:
    return {re.split(r"[<>=!~\[; ]", req, maxsplit=1)[0].lower() for req in requirements}


def test_pytest_extra_is_lean_and_the_plugin_is_declared() -> None:
    project = pyproject()["project"]
    assert _names(project["optional-dependencies"]["pytest"]) == {"pytest", "pytest-asyncio"}
    assert project["dependencies"] == ["pyserial-asyncio>=0.6"]  # runtime: stdlib + this
    assert "Framework :: Pytest" in project["classifiers"]
    assert project["entry-points"]["pytest11"] == {"gcu_async": "gcu_async.pytest_plugin"}


def _docs_setup_block() -> str:
    """The ``toml`` block of docs/pytest-plugin.md's "Set-up in a fresh project" section."""
    page = (ROOT / "docs" / "pytest-plugin.md").read_text(encoding="utf-8")
    section = page.split("## Set-up in a fresh project", 1)[1].split("\n## ", 1)[0]
    [block] = re.findall(r"```toml\n(.*?)```", section, re.DOTALL)
    return block


def _readme_plugin_example() -> str:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    part = readme.split("[start:plugin-example]", 1)[1].split("[end:plugin-example]", 1)[0]
    [code] = re.findall(r"```python\n(.*?)```", part, re.DOTALL)
    return code


def _run_fresh_project(path: Path, settings: str) -> subprocess.CompletedProcess[str]:
    (path / "pyproject.toml").write_text(
        f'[project]\nname = "fresh-app"\nversion = "0.1.0"\n\n{settings}', encoding="utf-8"
    )
    (path / "test_app.py").write_text(_readme_plugin_example(), encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider"],
        cwd=path,
        env=env,
        capture_output=True,
        text=True,
        timeout=90,
        check=False,
    )


def test_the_documented_setup_runs_the_plugin_in_a_fresh_project(tmp_path: Path) -> None:
    block = _docs_setup_block()
    assert tomllib.loads(block)["project"]["optional-dependencies"]["test"] == [
        "gcu-async[pytest]"
    ]
    proc = _run_fresh_project(tmp_path, block)
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output
    assert f"rootdir: {tmp_path}" in output, output  # its own configuration, not ours
    assert re.search(r"^plugins: .*\bgcu-async-", output, re.MULTILINE), output
    assert re.search(r"=+ 1 passed in ", output), output


def test_without_the_setup_the_async_test_does_not_run(tmp_path: Path) -> None:
    """What the docs say happens in pytest-asyncio's strict mode (so the set-up matters)."""
    proc = _run_fresh_project(tmp_path, "")
    output = proc.stdout + proc.stderr
    assert proc.returncode != 0, output
    assert "async def functions are not natively supported" in output, output
    assert " passed" not in output, output


# -- extras, dependency groups, metadata ------------------------------------------------------

USER_EXTRAS = {"pytest", "mavlink", "web", "capture"}


def test_only_user_extras_are_published_and_dev_tools_are_groups() -> None:
    data = pyproject()
    extras = data["project"]["optional-dependencies"]
    assert set(extras) == USER_EXTRAS  # no test/docs/bench extras next to the users' ones
    groups = data["dependency-groups"]
    assert {"test", "test-full", "lint", "docs", "dev"} <= set(groups)
    assert groups["dev"] == [{"include-group": g} for g in ("test", "test-full", "lint", "docs")]
    assert {"pytest-xdist", "pytest-timeout", "hypothesis"} <= _names(groups["test"])
    assert {"ruff", "mypy"} == _names(groups["lint"])
    # the fast tier's venvs (.ci/pythons.py) and `make test` install what the Makefile says
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    [user] = re.findall(r"^USER_EXTRAS := (\S+)$", makefile, re.MULTILINE)
    assert set(user.split(",")) == USER_EXTRAS - {"pytest"}  # the suite brings its own pytest
    assert re.search(r"^\t.*pip install --quiet -e \.$", makefile, re.MULTILINE)  # demo: alone


def test_metadata_names_the_operating_system() -> None:
    project = pyproject()["project"]
    assert all(url.startswith("https://") for url in project.get("urls", {}).values())
    assert "Operating System :: POSIX :: Linux" in project["classifiers"]


def _readme_extras_table() -> dict[str, set[str]]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    part = readme.split("<!-- extras-table:", 1)[1].split("\n\n", 1)[0]
    rows = re.findall(r"^\| `([\w-]+)` \| ([^|]+) \|", part, re.MULTILINE)
    return {name: {n.strip().lower() for n in adds.split(",")} for name, adds in rows}


def test_the_readme_lists_every_user_extra_with_what_it_adds() -> None:
    extras = pyproject()["project"]["optional-dependencies"]
    assert _readme_extras_table() == {name: _names(reqs) for name, reqs in extras.items()}


def _pypi_description() -> str:
    """The long description as hatch-fancy-pypi-readme assembles it from pyproject.toml."""
    config = pyproject()["tool"]["hatch"]["metadata"]["hooks"]["fancy-pypi-readme"]
    out = []
    for fragment in config["fragments"]:
        if "text" in fragment:
            out.append(fragment["text"])
            continue
        text = (ROOT / fragment["path"]).read_text(encoding="utf-8")
        assert text.count(fragment["start-after"]) == 1, fragment["start-after"]
        assert text.count(fragment["end-before"]) == 1, fragment["end-before"]
        text = text.split(fragment["start-after"], 1)[1]
        out.append(text.split(fragment["end-before"], 1)[0])
    return "".join(out)


def test_the_pypi_description_is_for_pip_users() -> None:
    assert "readme" in pyproject()["project"]["dynamic"]
    description = _pypi_description()
    assert description.startswith("# gcu_async\n\nasyncio driver, simulator and sans-I/O codec")
    assert "pip install gcu-async" in description
    assert "## Install and extras" in description and "## Quickstart" in description
    for checkout_only in ("make demo", "make test", "make check", "CONTRIBUTING.md", ".venv",
                          "checkout-only", "## Development", "## Examples"):  # fmt: skip
        assert checkout_only not in description, checkout_only
    # what the installed distribution carries is that text (`make test` reinstalls after a
    # change to pyproject.toml; an older install fails here until then)
    installed = importlib.metadata.metadata("gcu-async")
    assert installed["Description-Content-Type"] == "text/markdown"
    assert installed.get_payload().strip() == description.strip()  # type: ignore[attr-defined]
