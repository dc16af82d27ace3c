"""The page's forms, from the experiment descriptions (one source for page, CLI, notebook and docs).

Every option of ``motorlab analyze <experiment>`` (:mod:`motorlab.experiments`), ``motorlab
characterize`` and ``motorlab tune`` (:func:`motorlab.experiments._commands.command_options`) becomes a
JSON-ready field: its long name (the form field name and the HTTP API's field name), its label in
words, a one-line help, unit, default, choices and whether it is required. The same descriptions
generate the CLI's parsers, so the page and the CLI cannot disagree (tests/ui/test_api.py checks
the parsers against this). ``parameters`` names every result key in words; ``targets`` describes
``tune``'s targets.
"""

from __future__ import annotations

import functools
import math
import re
from typing import Any

from motorlab.cli.common import plain_text
from motorlab.experiments import Option, all_experiments
from motorlab.experiments._commands import command_options
from motorlab.units import format_unit

#: Options the app sets itself (output format, figure files): not form fields (docs/ui.md).
APP_OWNED = {"help", "json", "plot", "each", "emit", "output", "quiet", "no_report", "version"}

#: "(seed 1, "LCR Meter Experiment")": where an experiment comes from, for the docs, not the page.
_SEED = re.compile(r"\s*\(seed \d[^)]*\)")

#: Option kinds -> the page's input kinds.
_PAGE_KIND = {"flag": "flag", "choice": "choice", "files": "file"}


def _jsonable_default(value: Any) -> Any:
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


def _choice_labels(opt: Option) -> list[str] | None:
    """Each choice in words (:data:`motorlab.glossary.CHOICES`; a target's and a catalogue motor's own names)."""
    if not opt.choices:
        return None
    from motorlab.glossary import choice_words

    if opt.name == "target":
        from motorlab.control.targets import TARGET_INFO

        return [TARGET_INFO[c].label if c in TARGET_INFO else c for c in opt.choices]
    if opt.name == "motor":
        from motorlab.catalog import list_motors

        names = {m.key: m.name for m in list_motors()}
        return [names.get(c, c) for c in opt.choices]
    return [choice_words(opt.name, c) for c in opt.choices]


def field(opt: Option) -> dict[str, Any]:
    """One option (or positional argument) as a JSON-ready form field."""
    flag = opt.kind == "flag"
    unit = opt.unit if opt.unit not in (None, "1", "count") else ""
    return {
        "name": opt.key if opt.positional else opt.name,
        "dest": opt.key,
        "option": None if opt.positional else f"--{opt.name}",
        "aliases": [f"--{a}" for a in opt.aliases],
        "positional": opt.positional,
        "kind": _PAGE_KIND.get(opt.kind, "text"),
        "type": opt.kind,
        "label": opt.label,
        "help": plain_text(opt.help),
        "unit": unit,
        "unit_display": format_unit(unit) if unit else "",
        "default": None if flag else _jsonable_default(opt.default),
        "choices": list(opt.choices) if opt.choices else None,
        "choice_labels": _choice_labels(opt),
        "required": opt.required,
        "repeatable": opt.kind in ("files", "columns", "spans"),  # --column: one rule per column
        "positive": opt.positive,
        "nonnegative": opt.nonnegative,
        "group": opt.group,
        "metavar": opt.metavar,
    }


#: The measurement files of ``analyze`` (its positional argument, described by the CLI).
FILES = Option("files", kind="files", positional=True, required=True, metavar="FILE", label="Measurement files",
               help="the log or logs of one run (a run split over several files: give them all)")


#: What ``characterize`` and ``tune`` do, in a line.
DESCRIPTIONS = {
    "characterize": "Every experiment of a session on every unit: the results table, the fleet check and the report",
    "tune": "Feedback and feedforward gains for a velocity or position loop, in the units of the controller "
            "that runs them, checked in a closed-loop simulation",
}


@functools.cache
def schema() -> dict[str, Any]:
    """``{"analyze": {experiment: {...}}, "characterize": {...}, "tune": {...}, "parameters", "targets", "tasks",
    "gains", "measured_by", "plain_words"}``: every word the page shows for what the descriptions and the
    glossary name."""
    from motorlab.control.targets import TARGET_INFO
    from motorlab.glossary import GAINS, MEASURED_BY, PARAMETERS, PLAIN_WORDS, TASKS

    analyze = {
        name: {
            "title": exp.title or name,
            "description": _SEED.sub("", plain_text(exp.summary)),
            "inputs": plain_text(exp.inputs),
            "reports": list(exp.reports),
            "fields": [field(FILES), *(field(opt) for opt in exp.options)],
        }
        for name, exp in all_experiments().items()
    }
    return {
        "analyze": analyze,
        **{
            command: {
                "description": DESCRIPTIONS[command],
                "fields": [field(opt) for opt in command_options(command)],
            }
            for command in ("characterize", "tune")
        },
        "parameters": {key: p.to_dict() for key, p in PARAMETERS.items()},
        "targets": [info.to_dict() for info in TARGET_INFO.values()],
        "tasks": {key: task.to_dict() for key, task in TASKS.items()},
        "gains": dict(GAINS),
        "measured_by": dict(MEASURED_BY),
        "plain_words": [list(pair) for pair in PLAIN_WORDS],
    }


def command_fields(command: str, experiment: str | None = None) -> list[dict[str, Any]]:
    """The fields of ``analyze <experiment>``, ``characterize`` or ``tune`` (KeyError when unknown)."""
    s = schema()
    return list(s["analyze"][experiment or ""]["fields"]) if command == "analyze" else list(s[command]["fields"])
