"""Fuzz cases for the app's upload endpoints (``/api/analyze``, ``/api/detect``, ``/api/tune``, ``/api/characterize``).

Requests go through Starlette's ``TestClient`` on :func:`motorlab.ui.app.create_app`: the app's own
form parsing, upload naming, zip unpacking and argv building run as they do for a browser, and the
command runs in its child process as always. The promise: a 2xx answer with JSON that parses (no
NaN), or a 4xx ``{"error": one line}``; never a 5xx, a traceback or an error of several lines.
"""

from __future__ import annotations

import contextlib
import io
import json
import warnings
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from fuzz_corpus import Seed
from fuzz_mutate import Chooser, mutators_for

FORMS = ("analyze", "analyze", "detect", "tune", "characterize", "garbage-body", "zip")
NAMES = ("../../etc/passwd", "", ".hidden.csv", "a" * 300 + ".csv", "x\x00y.csv", "é.csv", "con", "a/b/../../c.csv")
VALUES = ("9**9**9", "2**1024", "1e-12", "", "nan", "-1", "\x00", "1" * 5000, "1e308", "3 furlongs")


@contextlib.contextmanager
def app_client() -> Iterator[Any]:
    """A ``TestClient`` on a new app, as a browser on 127.0.0.1 would reach it."""
    with warnings.catch_warnings():  # starlette would rather have "httpx2"; httpx is what the project installs
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient
    from motorlab.ui.app import create_app

    with TestClient(create_app(), base_url="http://127.0.0.1:8765") as client:
        yield client


def judge_response(response: Any) -> tuple[str, str]:
    """``("ok"|"refused", detail)`` when the promise is kept, else the failure's class and detail."""
    if response.status_code >= 500:
        return "app-5xx", f"{response.status_code} {response.text[:300]}"
    if not response.headers.get("content-type", "").startswith("application/json"):
        return ("ok", "") if response.status_code < 400 else ("app-not-json", response.text[:300])
    try:
        body = json.loads(response.text, parse_constant=lambda name: (_ for _ in ()).throw(ValueError(name)))
    except ValueError as exc:
        return "bad-json", str(exc)[:200]
    if response.status_code < 400:
        return "ok", ""
    error = body.get("error") if isinstance(body, dict) else None
    if not isinstance(error, str) or not error.strip() or "\n" in error or "Traceback" in error:
        return "not-one-line", repr(error)[:300]
    if "internal error" in error:
        return "internal-error", error[:300]
    return "refused", error


def app_case(client: Any, corpus: Path, seeds: list[Seed], c: Chooser) -> tuple[str, str, str]:
    """One request with mutated uploads, file names and fields: (verdict, detail, what was sent)."""
    form = c.choice(list(FORMS))
    fast = [s for s in seeds if s.command[0] == "analyze" and s.files and not s.real and not s.slow]
    seed = c.choice(fast)
    name = seed.files[0]
    content = (corpus / name).read_bytes()
    if c.choice([True, True, False]):
        table = mutators_for(seed.kind)
        content = table[c.choice(sorted(table))](content, c)
    filename = c.choice([name, name, *NAMES])
    fields = {opt[2:]: val for opt, val in zip(seed.options[::2], seed.options[1::2], strict=False)}
    if c.choice([False, True]):
        fields[c.choice(["cpr", "K", "inertia", "current", "plot", "output", "json", "no-such"])] = c.choice(VALUES)
    what = f"{form} {seed.name} {filename[:40]!r} {str(fields)[:80]}"
    if form == "garbage-body":
        response = client.post(f"/api/analyze/{seed.command[1]}", content=content[:5000],
                               headers={"content-type": c.choice(["multipart/form-data; boundary=x",
                                                                  "application/json", "text/plain"])})
    elif form == "zip":
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w") as zf:
            zf.writestr(c.choice([name, "../evil.csv", "/abs.csv", "d/" * 50 + "x.csv"]), content)
        raw = buffer.getvalue()
        raw = raw if c.choice([True, False]) else mutators_for("binary")["flip-bytes"](raw, c)
        response = client.post("/api/detect", files=[("file", ("logs.zip", raw))])
    elif form == "detect":
        response = client.post("/api/detect", files=[("file", (filename, content))])
    elif form == "tune":
        params = (corpus / "params.json").read_bytes()
        params = mutators_for("json")[c.choice(sorted(mutators_for("json")))](params, c)
        response = client.post("/api/tune", files=[("params", ("params.json", params))],
                               data={c.choice(["kv", "ka", "target", "loop"]): c.choice(VALUES)})
    elif form == "characterize":
        toml = (corpus / "session.toml").read_bytes()
        toml = mutators_for("toml")[c.choice(sorted(mutators_for("toml")))](toml, c)
        files = [("file", ("session.toml", toml))] + [("file", (n, (corpus / n).read_bytes()))
                                                       for n in ("lcr.csv", "terminal.csv", "torque.csv")]
        response = client.post("/api/characterize", files=files)
    else:
        response = client.post(f"/api/analyze/{seed.command[1]}", files=[("file", (filename, content))], data=fields)
    verdict, detail = judge_response(response)
    return verdict, detail, what
