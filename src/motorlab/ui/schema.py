"""The page's forms, read off the CLI's own argparse parsers (one source for page, CLI and session).

Every option of ``motorlab analyze <experiment>``, ``motorlab characterize`` and ``motorlab tune``
becomes a JSON-ready field: its long name (the form field name and the HTTP API's field name),
unit, default, help, choices and whether it is required. Nothing here restates an option: a new or
changed option of the CLI shows on the page as it is.
"""

from __future__ import annotations

import argparse
import functools
import math
import re
from typing import Any

from motorlab.cli.common import plain_text

#: Options the app sets itself (output format, figure files): not shown as form fields.
APP_OWNED = {"help", "json", "plot", "each", "emit", "output", "quiet", "no_report", "version"}

_UNIT_IN_HELP = re.compile(r"\[([^\[\]]+)\]")


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse keeps sub-parsers only here
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _unit(action: argparse.Action) -> str:
    """The unit of an option: from its ``quantity(...)`` type, else the last ``[...]`` of its help."""
    name = getattr(action.type, "__name__", "")
    if name.startswith("quantity in "):
        return name.removeprefix("quantity in ")
    found = _UNIT_IN_HELP.findall((action.help or "").replace("%%", "%"))
    return found[-1] if found else ""


def _jsonable_default(value: Any) -> Any:
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


def _is_file(action: argparse.Action) -> bool:
    return action.dest in ("files", "session") or "FILE" in str(action.metavar or "")


def field(action: argparse.Action) -> dict[str, Any]:
    """One option (or positional argument) as a JSON-ready form field."""
    long = next((s for s in action.option_strings if s.startswith("--")), None)
    name = (long or (action.option_strings or [action.dest])[0]).lstrip("-")
    flag = isinstance(action, argparse._StoreTrueAction)
    kind = "flag" if flag else "choice" if action.choices else "file" if _is_file(action) else "text"
    return {
        "name": name,
        "dest": action.dest,
        "option": long or (action.option_strings[0] if action.option_strings else None),
        "positional": not action.option_strings,
        "kind": kind,
        "unit": _unit(action),
        "default": None if flag else _jsonable_default(action.default),
        "help": plain_text((action.help or "").replace("%%", "%")),
        "choices": list(action.choices) if action.choices else None,
        "required": bool(action.required) or (not action.option_strings and action.nargs not in ("?", "*")),
        "repeatable": isinstance(action, argparse._AppendAction) or action.nargs in ("+", "*"),
        "metavar": action.metavar if isinstance(action.metavar, str) else None,
    }


def fields(parser: argparse.ArgumentParser) -> list[dict[str, Any]]:
    """The form fields of one command's parser (the options the app sets itself left out)."""
    return [
        field(action)
        for action in parser._actions
        if action.dest not in APP_OWNED and not isinstance(action, argparse._SubParsersAction)
    ]


@functools.cache
def schema() -> dict[str, Any]:
    """``{"analyze": {experiment: {...}}, "characterize": {...}, "tune": {...}}`` from the CLI parsers."""
    from motorlab.cli import build_parser

    commands = _subparsers(build_parser())
    analyze = {
        name: {"description": plain_text(p.description or ""), "fields": fields(p)}
        for name, p in _subparsers(commands["analyze"]).items()
    }
    return {
        "analyze": analyze,
        **{
            command: {
                "description": plain_text(commands[command].description or ""),
                "fields": fields(commands[command]),
            }
            for command in ("characterize", "tune")
        },
    }


def command_fields(command: str, experiment: str | None = None) -> list[dict[str, Any]]:
    """The fields of ``analyze <experiment>``, ``characterize`` or ``tune`` (KeyError when unknown)."""
    s = schema()
    return s["analyze"][experiment or ""]["fields"] if command == "analyze" else s[command]["fields"]
