"""Reading a command's JSON body, bounded: :func:`read_json`.

The body must be declared ``application/json`` (a browser can send ``text/plain`` or a form
to any address without asking first; it cannot send ``application/json`` cross-origin
without a CORS preflight, which this app never answers). Its size is checked against the
limit while it arrives (``Content-Length`` first, then every chunk), so an endless body
costs at most the limit plus one chunk. Nesting is bounded before parsing (a command's
parameters are one object holding at most a flat array), duplicate keys are refused
(the later one would silently win) and so is anything that is not UTF-8 JSON text.
"""

from __future__ import annotations

import json
from typing import Any

from starlette.requests import Request

DEFAULT_MAX_BODY = 16 * 1024
"""Bytes a command body may have: the longest real one is well under 200."""
MAX_DEPTH = 8
"""Deepest nesting of arrays and objects accepted (a command body needs 2)."""
JSON_TYPE = "application/json"


class BodyError(Exception):
    """A body refused before use: HTTP status, ``kind`` and message."""

    def __init__(self, status: int, kind: str, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.kind = kind


def _check_type(value: str | None) -> None:
    media, _, params = (value or "").partition(";")
    charset = ""
    for param in params.split(";"):
        key, _, val = param.partition("=")
        if key.strip().lower() == "charset":
            charset = val.strip().strip('"').lower()
    if media.strip().lower() != JSON_TYPE or charset not in ("", "utf-8"):
        raise BodyError(415, "UnsupportedMediaType", f"Content-Type: {value!r} is not allowed: "
                        f"send {JSON_TYPE} (UTF-8), even for an empty body")  # fmt: skip


async def read_bounded(request: Request, limit: int) -> bytes:
    """The body, read chunk by chunk; :class:`BodyError` 413 as soon as it passes ``limit``
    bytes (the rest is never read)."""
    declared = request.headers.get("content-length")
    if declared is not None:
        if not declared.isdigit():
            raise BodyError(400, "BadRequest", f"Content-Length: {declared[:40]!r} is not a "
                            "byte count")  # fmt: skip
        if int(declared) > limit:
            raise BodyError(413, "PayloadTooLarge", f"body: {declared} bytes is outside the "
                            f"allowed range [0, {limit}] bytes")  # fmt: skip
    chunks: list[bytes] = []
    size = 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > limit:
            raise BodyError(413, "PayloadTooLarge", f"body: more than {limit} bytes (the "
                            f"allowed range is [0, {limit}] bytes)")  # fmt: skip
        chunks.append(chunk)
    return b"".join(chunks)


def nesting_depth(text: str) -> int:
    """The deepest nesting of ``[``/``{`` in JSON text (brackets inside strings ignored)."""
    depth = deepest = 0
    in_string = escaped = False
    for ch in text:
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth -= 1
    return deepest


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    result: dict[str, Any] = {}
    for key, value in pairs:
        if key in result:
            raise ValueError(f"duplicate key {key!r}")
        result[key] = value
    return result


def parse_json(raw: bytes) -> object:
    """The decoded body (``{}`` for an empty one: all defaults; JSON ``null`` is not an
    empty body); :class:`BodyError` 400 naming what is wrong."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise BodyError(400, "BadRequest", f"the body is not UTF-8: {exc}") from None
    if not text.strip():
        return {}
    depth = nesting_depth(text)
    if depth > MAX_DEPTH:
        raise BodyError(400, "BadRequest", f"the body is not valid JSON for a command: nesting "
                        f"depth {depth} is outside the allowed range [0, {MAX_DEPTH}]")  # fmt: skip
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates)
    except ValueError as exc:  # JSONDecodeError, duplicate keys, > 4300-digit integers
        raise BodyError(400, "BadRequest", f"the body is not valid JSON: {exc}") from None


async def read_json(request: Request, limit: int = DEFAULT_MAX_BODY) -> object:
    """The request's JSON body (``{}`` when empty), checked as the module says."""
    _check_type(request.headers.get("content-type"))
    return parse_json(await read_bounded(request, limit))
