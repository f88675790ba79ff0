"""``python -m examples.web``'s security options: ``--token`` (and ``GCU_WEB_TOKEN``,
``--token auto``) and ``--allowed-host`` (and ``GCU_WEB_ALLOWED_HOSTS``): checked before
anything starts (usage errors exit 2 with one line), and, in the real entry point, the
printed console URL carries the token the API then needs."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from helpers.examples.web_deps import require_web

require_web()
import httpx  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # the examples live beside src/, not inside the package
    sys.path.insert(0, str(ROOT))

from examples.web.__main__ import parse_args  # noqa: E402


@pytest.fixture(autouse=True)
def _clean_env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("GCU_WEB_TOKEN", raising=False)
    monkeypatch.delenv("GCU_WEB_ALLOWED_HOSTS", raising=False)


@pytest.mark.parametrize("token", ["short", "has space 0123456789", "x" * 257])
def test_a_bad_token_is_a_usage_error(token: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as caught:
        parse_args(["--sim", "--token", token])
    assert caught.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--token: token: expected 16 to 256 characters" in err
    assert token not in err


def test_token_from_the_environment_and_auto(monkeypatch: pytest.MonkeyPatch) -> None:
    assert parse_args(["--sim"]).token is None
    monkeypatch.setenv("GCU_WEB_TOKEN", "from-the-environment-0123")
    assert parse_args(["--sim"]).token == "from-the-environment-0123"
    assert parse_args(["--sim", "--token", "from-the-command-line-0123"]).token == (
        "from-the-command-line-0123"
    )
    auto = parse_args(["--sim", "--token", "auto"]).token
    assert auto != parse_args(["--sim", "--token", "auto"]).token  # random each time
    assert re.fullmatch(r"[A-Za-z0-9_-]{32}", auto)


def test_allowed_hosts(monkeypatch: pytest.MonkeyPatch) -> None:
    assert parse_args(["--sim"]).allowed_hosts == {"127.0.0.1", "localhost", "::1"}
    monkeypatch.setenv("GCU_WEB_ALLOWED_HOSTS", "gimbal.lan, pod.local")
    args = parse_args(["--sim", "--allowed-host", "ops.example", "--host", "127.0.0.5"])
    assert args.allowed_hosts == {"127.0.0.1", "localhost", "::1", "gimbal.lan", "pod.local",
                                  "ops.example", "127.0.0.5"}  # fmt: skip
    # a wildcard bind address is no name a browser sends
    assert "0.0.0.0" not in parse_args(["--sim", "--host", "0.0.0.0"]).allowed_hosts


def test_the_entry_point_prints_the_url_with_its_token() -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    env.pop("GCU_WEB_TOKEN", None)
    process = subprocess.Popen(
        [sys.executable, "-m", "examples.web", "--sim", "--port", "0", "--token", "auto"],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        assert process.stdout is not None
        deadline = time.monotonic() + 15.0
        url = port = None
        while (url is None or port is None) and time.monotonic() < deadline:
            line = process.stdout.readline()
            assert line, "the console ended before it started"
            if match := re.match(r"console: http://127\.0\.0\.1:(\d+)/#token=(\S+)$",
                                 line.strip()):  # fmt: skip
                url, port, token = match.group(0), int(match.group(1)), match.group(2)
        assert url is not None and port is not None, "no console URL or port printed"
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=5.0) as http:
            assert http.get("/api/commands").status_code == 401
            headers = {"authorization": f"Bearer {token}"}
            assert http.get("/api/commands", headers=headers).status_code == 200
    finally:
        process.terminate()
        try:
            process.communicate(timeout=10.0)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()


def test_app_from_env_takes_the_token_and_hosts(monkeypatch: pytest.MonkeyPatch) -> None:
    from examples.web.app import app_from_env

    monkeypatch.setenv("GCU_LOCAL_PORT", "0")
    monkeypatch.setenv("GCU_WEB_TOKEN", "env-token-0123456789abcdef")
    monkeypatch.setenv("GCU_WEB_ALLOWED_HOSTS", "gimbal.lan,,pod.local ")
    policy = app_from_env().state.policy
    assert policy.token == "env-token-0123456789abcdef"
    assert policy.allowed_hosts == {"127.0.0.1", "localhost", "::1", "gimbal.lan", "pod.local"}
    monkeypatch.setenv("GCU_WEB_TOKEN", "")  # empty: no token
    assert app_from_env().state.policy.token is None
    monkeypatch.setenv("GCU_WEB_TOKEN", "too-short")
    with pytest.raises(ValueError, match="token: expected 16 to 256 characters"):
        app_from_env()


def test_the_page_uses_the_servers_names_for_the_token() -> None:
    """app.js cannot import guard.py: the subprotocol names and the token's characters it
    uses are checked here against the server's."""
    from examples.web.guard import TOKEN_PATTERN, WS_PROTOCOL, WS_TOKEN_PREFIX

    script = (ROOT / "examples" / "web" / "static" / "app.js").read_text(encoding="utf-8")
    assert f'"{WS_PROTOCOL}"' in script
    assert f"`{WS_TOKEN_PREFIX}${{TOKEN}}`" in script
    characters = TOKEN_PATTERN.pattern.split("{")[0]  # "[A-Za-z0-9._~-]"
    assert f"token=({characters}+)" in script
