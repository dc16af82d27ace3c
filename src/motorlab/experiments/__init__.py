"""One declarative description per experiment: what it reads, its options, what it reports.

Every module of this package (``motorlab/experiments/<name>.py``) defines ``EXPERIMENT``, an
:class:`Experiment` (or ``EXPERIMENTS``, a tuple, for related ones: ``gains.py`` describes the
amplifier and the tachometer); adding an experiment is adding one module. From these descriptions come:

* the ``motorlab analyze`` sub-commands and their options (:mod:`motorlab.cli.analyze`),
* the notebook functions ``ml.<name>(files, **options)`` (:mod:`motorlab.notebook`),
* the session file's experiment tables and their settings (:mod:`motorlab.session.spec`),
* ``characterize``'s run order, adapters and what each experiment contributes to the final table
  (:mod:`motorlab.session.characterize`), and the experiments a simulated session runs on the virtual rig,
* the option tables of docs/analyze.md (checked by ``tests/experiments/test_registry.py``).

:meth:`Experiment.schema` is the JSON-able form (for the browser app's forms, issue 19).
Values are SI; a quantity option takes a number (SI) or a string with a unit (parsed by pint).
"""

from __future__ import annotations

import importlib
import math
import os
import pkgutil
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from motorlab import progress
from motorlab.errors import OptionError
from motorlab.units import format_unit, parse_quantity

if TYPE_CHECKING:
    from motorlab.results import Estimate, FitResult

#: At what temperature an R holds when the analysis does not know the winding's (every one but stall).
R_AS_MEASURED = ("R holds at the winding's temperature during the measurement, which was not measured: copper's "
                 "R rises 0.393 % per kelvin, so a warm winding reads high (analyze stall gives R at 25 °C)")
#: Kinds of option value: a number with a unit (pint), one of some words, true/false, paths, a whole
#: number, a plain number (its unit depends on other options, e.g. tune's kV per ``--units``), text.
KINDS = ("quantity", "choice", "flag", "files", "int", "number", "text", "columns", "spans")


@dataclass(frozen=True)
class Option:
    """One option of an experiment (a ``--name`` of ``motorlab analyze``, a keyword of ``ml.<name>``).

    Parameters
    ----------
    name
        The CLI's long option without dashes (``inertia-stderr``); the notebook keyword is the same
        with ``_`` for ``-``.
    unit
        SI unit of a quantity (``"kg*m^2"``, ``""`` for a pure number) [-].
    default
        Value when the option is not given (SI), or None.
    help
        One line for ``--help``, the docs' tables and the browser's forms: what to give, in words, no
        default and no unit (both are shown beside it; the CLI's ``--help`` appends them).
    label
        The field's name in words, as a form shows it ("Encoder counts per revolution").
    kind
        ``"quantity"`` (a number with a unit), ``"choice"``, ``"flag"`` (true/false), ``"files"``
        (one or more paths), ``"int"``, ``"columns"`` (column rules ``HEADER=quantity``, repeatable:
        :mod:`motorlab.io.headers`; the value is a list of rules as text) or ``"spans"`` (time spans
        ``start:end`` in seconds of the log's time, repeatable: :mod:`motorlab.timespans`; the value is
        a list of ``(start, end)``).
    dest
        Name of the value handed to the experiment's ``run`` (default: ``name`` with ``_``). A flag
        whose default is True is switched off by ``--name`` (``--no-current`` sets ``use_current``
        False).
    aliases
        Other CLI spellings (``("K",)`` for ``Km``).
    positional
        A positional argument of the command (``tune``'s loop), not a ``--name`` option.
    """

    name: str
    unit: str | None = None
    default: Any = None
    help: str = ""
    kind: str = "quantity"
    choices: tuple[str, ...] | None = None
    positive: bool = False
    nonnegative: bool = False
    required: bool = False
    dest: str | None = None
    aliases: tuple[str, ...] = ()
    metavar: str | None = None
    group: str | None = None
    label: str = ""
    positional: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"option {self.name}: unknown kind {self.kind!r}")
        if self.kind == "quantity" and self.unit is None:
            raise ValueError(f"option {self.name}: a quantity needs a unit ('' for a pure number)")

    @property
    def key(self) -> str:
        """The value's name in ``run``'s mapping."""
        return self.dest or self.name.replace("-", "_")

    @property
    def keywords(self) -> tuple[str, ...]:
        """Every keyword the notebook accepts for this option."""
        names = [n.replace("-", "_") for n in (self.name, *self.aliases)]
        return tuple(dict.fromkeys([*names, self.key]))

    def convert(self, value: Any, *, label: str | None = None) -> Any:
        """``value`` (SI number, string with a unit, name of a choice ...) as this option's SI value.

        Raises
        ------
        OptionError
            Naming ``label`` (default: the option's name) and what is wrong.
        """
        label = label or self.name
        if value is None:
            return None
        if self.kind == "flag":
            if not isinstance(value, bool):
                raise OptionError(f"{label}: expected True or False, got {value!r}")
            return value
        if self.kind == "choice":
            assert self.choices is not None
            if value not in self.choices:
                raise OptionError(f"{label}: {value!r} is not one of {', '.join(self.choices)}")
            return value
        if self.kind == "files":
            items = [value] if isinstance(value, str) or hasattr(value, "__fspath__") else list(value)
            return [str(item) for item in items]
        if self.kind == "text":
            return str(value)
        if self.kind == "columns":
            from motorlab.io.headers import parse_column_mapping

            return [rule.text() for rule in parse_column_mapping(value, name=label)] or None
        if self.kind == "spans":
            from motorlab.timespans import parse_spans

            return parse_spans(value, name=label) or None
        if self.kind == "number":
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise OptionError(f"{label}: {value!r} is not a number") from None
            if not math.isfinite(number):
                raise OptionError(f"{label}: {value!r} is not a finite number")
            return self._check_sign(number, value, label)
        if self.kind == "int":
            text = value.strip() if isinstance(value, str) else None
            if text is not None and not (text.lstrip("+-").isdigit() and text.isascii()):
                raise OptionError(f"{label}: {value!r} is not a whole number")  # int() would take "1_0"
            if text is None and (isinstance(value, bool) or not isinstance(value, int | float)
                                 or not math.isfinite(value) or value != int(value)):
                raise OptionError(f"{label}: {value!r} is not a whole number")
            return self._check_sign(int(text if text is not None else value), value, label)
        assert self.unit is not None
        return self._check_sign(parse_quantity(value, self.unit, name=label), value, label)

    def _check_sign(self, number: float, given: Any, label: str) -> Any:
        if self.positive and not number > 0:
            raise OptionError(f"{label}: {given!r} must be positive")
        if self.nonnegative and not number >= 0:
            raise OptionError(f"{label}: {given!r} must not be negative")
        return number

    @property
    def cli_help(self) -> str:
        """The ``--help`` line: the label, :attr:`help`, the unit and the default (``%`` escaped for argparse)."""
        text = f"{self.label}: {self.help}" if self.label and self.help else self.label or self.help
        if self.unit and self.unit not in ("1", "count"):
            text += f" [{format_unit(self.unit)}]"
        if self.default is not None and self.kind not in ("flag", "files", "columns", "spans"):
            shown = f"{self.default:g}" if isinstance(self.default, float) else str(self.default)
            text += f" (default {shown})"
        return text.replace("%", "%%")

    def schema(self) -> dict[str, Any]:
        """JSON-able description."""
        default = self.default
        if isinstance(default, float) and not math.isfinite(default):
            default = None
        return {
            "name": self.name, "keyword": self.key, "aliases": list(self.aliases), "kind": self.kind,
            "label": self.label, "unit": self.unit, "unit_display": format_unit(self.unit) if self.unit else self.unit,
            "default": default, "choices": list(self.choices) if self.choices else None,
            "positive": self.positive, "nonnegative": self.nonnegative, "required": self.required,
            "help": self.help, "group": self.group, "positional": self.positional,
        }


@dataclass(frozen=True)
class Setting:
    """A key of the experiment's table in a session file (besides ``files``).

    ``kind`` is an SI unit (a quantity read with pint) or ``"int"``, ``"float"``, ``"str"``.
    """

    name: str
    kind: str
    help: str
    required: bool = False


@dataclass(frozen=True)
class RigRun:
    """How the virtual dynamometer produces the experiment's file for a simulated session.

    ``experiment`` is the rig's name for it (:mod:`motorlab.rig`), ``file`` the file name written,
    ``settings`` the rig's settings, ``order`` its place in a simulated session (the rig's noise is
    drawn in this order, so a session's files depend on it).
    """

    experiment: str
    file: str
    settings: Mapping[str, Any] = field(default_factory=dict)
    order: int = 100


#: The key of :meth:`Experiment.in_session`'s values that holds the unit's earlier fits (by experiment name):
#: ``run(paths, values)`` uses ``values.get(FITS, {})`` where a session gives it more than an option can say.
FITS = "fits"
#: Likewise the unit's estimates so far (by symbol): what fills in where a command would need an option.
KNOWN = "known"


@dataclass(frozen=True)
class FromSession:
    """What a session gives an experiment's ``run``.

    Parameters
    ----------
    options
        Option values by keyword, as a notebook caller gives them (SI numbers or strings with units);
        None is left out (the option's default holds).
    fits
        Earlier results of the unit that the run may use (``"spindown"``, …).
    known
        The unit's estimates so far (``"R"``, ``"K"`` …) that the run may fall back on where the file lacks
        what a command's option would give (identify's R and K for a log without current).
    notes
        What the session contributed, said in the result's warnings.
    """

    options: Mapping[str, Any]
    fits: Mapping[str, Any] = field(default_factory=dict)
    known: Mapping[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class Experiment:
    """The description of one experiment.

    Parameters
    ----------
    name
        The CLI name (``motorlab analyze NAME``, the session table ``[units.A.NAME]``).
    title
        Its name in words, for a person choosing it ("Flywheel spin-down").
    summary
        One line (the sub-command's help).
    analysis
        The library function, ``"module:function"``.
    inputs
        What the files are (format and columns with units).
    run
        ``run(paths, values) -> FitResult``: reads the files and calls the analysis with the
        options' values (by :attr:`Option.key`, SI, defaults filled in).
    options
        The options, in the order of ``--help``.
    reports
        Symbols of the parameters the result holds (when the data determine them).
    shaft
        Which shaft, load and torque units the figures refer to (docs/gearbox.md).
    order
        Position in ``characterize``'s run order (sources of K first).
    settings
        Keys of the session file's table.
    contributes
        Result parameter -> motor parameter of the final table.
    loaded
        Run with the flywheel attached (its J, b, Tf include the flywheel and gearbox).
    session
        ``session(ctx) -> FromSession``: the option values a session's table and what the unit has
        measured so far give :attr:`run` (:mod:`motorlab.session.characterize`). A session runs the very
        ``run`` the CLI and the notebook call (:meth:`in_session`): one analysis path per experiment.
    rig
        How the virtual rig produces the experiment's file, or None.
    """

    name: str
    summary: str
    analysis: str
    inputs: str
    run: Callable[[list[str], dict[str, Any]], FitResult]
    options: tuple[Option, ...] = ()
    reports: tuple[str, ...] = ()
    shaft: str = ""
    order: int = 100
    settings: tuple[Setting, ...] = ()
    contributes: Mapping[str, str] = field(default_factory=dict)
    loaded: bool = False
    session: Callable[[Any], FromSession] | None = None
    rig: RigRun | None = None
    title: str = ""

    def option(self, keyword: str) -> Option:
        """The option a notebook keyword or CLI name stands for."""
        for opt in self.options:
            if keyword in opt.keywords or keyword == opt.name:
                return opt
        if keyword == "exclude":  # time spans: only the analyses of logs with a time axis take them
            raise OptionError(f"{self.name}: {exclude_hint()}")
        known = ", ".join(opt.key for opt in self.options)
        raise OptionError(f"{self.name}: unknown option {keyword!r}; known: {known}")

    def values(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """Every option's value (SI) from keywords (converted and checked) and the defaults."""
        values = {opt.key: opt.default for opt in self.options}
        seen: dict[str, str] = {}
        for keyword, value in given.items():
            opt = self.option(keyword)
            if opt.key in seen:
                raise OptionError(f"{self.name}: {keyword} and {seen[opt.key]} are the same option")
            seen[opt.key] = keyword
            values[opt.key] = opt.convert(value, label=keyword)
            if opt.kind == "flag" and opt.default is True and keyword != opt.key:
                values[opt.key] = not values[opt.key]  # no_current=True is use_current=False
        missing = [opt.name.replace("-", "_") for opt in self.options if opt.required and values[opt.key] is None]
        if missing:
            raise OptionError(f"{self.name}: give {', '.join(missing)}")
        return values

    def analyze(self, paths: Sequence[str], values: Mapping[str, Any]) -> FitResult:
        """Run the analysis on ``paths`` with option ``values`` (as :meth:`values` returns them).

        The same file given twice (also under two names) is refused: its rows would count twice.
        """
        from motorlab.io.headers import column_mapping
        from motorlab.io.text import check_distinct

        check_distinct(paths)
        names = ", ".join(os.path.basename(str(p)) for p in paths)
        # --column: every CSV read by the run honours it. The task shows the analysis under way (the
        # readers and the long fits report their own steps inside it).
        with column_mapping(values.get("columns")), progress.task(f"Analysing {names}", detail=self.name):
            result = self.run([str(p) for p in paths], dict(values))
        if self.shaft:
            result.details.setdefault("shaft", self.shaft)
        if any(name in result.parameters for name in ("R", "R_dc")):
            # Every R says at what temperature it holds (analyze stall: 25 °C; the others: as measured).
            result.details.setdefault("R_temperature", R_AS_MEASURED)
        result.check_physics()  # also what the run added after the analysis made its result
        return result

    def in_session(self, ctx: Any) -> FitResult:
        """Run the analysis for a unit of a session: :attr:`session`'s option values through :meth:`analyze`.

        The session's answer is the command's answer for the same files and options, warnings included;
        what the unit contributed (its K, an earlier fit) is said in the result's warnings.

        Raises
        ------
        OptionError
            The experiment takes no part in a session, or a value it needs is missing.
        """
        if self.session is None:
            raise OptionError(f"{self.name} takes no part in a session")
        given = self.session(ctx)
        values = self.values({key: value for key, value in given.options.items() if value is not None})
        values[FITS], values[KNOWN] = dict(given.fits), dict(given.known)
        result = self.analyze(ctx.files, values)
        result.warnings.extend(note for note in given.notes if note not in result.warnings)
        return result

    def schema(self) -> dict[str, Any]:
        """JSON-able description (for forms and documentation)."""
        return {
            "name": self.name, "title": self.title or self.name, "summary": self.summary, "analysis": self.analysis,
            "inputs": self.inputs,
            "options": [opt.schema() for opt in self.options], "reports": list(self.reports), "shaft": self.shaft,
            "session": {
                "order": self.order, "loaded": self.loaded, "contributes": dict(self.contributes),
                "settings": [{"name": s.name, "kind": s.kind, "help": s.help, "required": s.required}
                             for s in self.settings],
            },
            "rig": None if self.rig is None else {"experiment": self.rig.experiment, "file": self.rig.file,
                                                  "settings": dict(self.rig.settings), "order": self.rig.order},
        }


_REGISTRY: dict[str, Experiment] = {}


def all_experiments() -> dict[str, Experiment]:
    """Every experiment, by name, in ``characterize``'s run order (each module of this package)."""
    if not _REGISTRY:
        found: list[Experiment] = []
        for info in pkgutil.iter_modules(__path__):
            if info.name.startswith("_"):
                continue
            module = importlib.import_module(f"{__name__}.{info.name}")
            found.extend(getattr(module, "EXPERIMENTS", None) or (module.EXPERIMENT,))
        for exp in sorted(found, key=lambda e: (e.order, e.name)):
            _REGISTRY[exp.name] = exp
    return dict(_REGISTRY)


def get(name: str) -> Experiment:
    """The experiment called ``name``.

    Raises
    ------
    OptionError
        An unknown name (the known ones listed).
    """
    experiments = all_experiments()
    if name not in experiments:
        raise OptionError(f"unknown experiment {name!r}; known: {', '.join(experiments)}")
    return experiments[name]


def schema() -> dict[str, Any]:
    """Every experiment's :meth:`Experiment.schema`, by name (JSON-able)."""
    return {name: exp.schema() for name, exp in all_experiments().items()}


def exclude_hint() -> str:
    """What to do when an analysis that takes no time spans is given some (``--exclude``)."""
    takes = [name for name, exp in all_experiments().items() if any(o.kind == "spans" for o in exp.options)]
    return (f"time spans are left out by analyze {', '.join(sorted(takes))} only (a log with a time axis); "
            "for another analysis, leave the rows out of a copy of the file")


def stderr_or_none(est: Estimate) -> float | None:
    """A usable standard error (finite, ≥ 0) or None."""
    return est.stderr if math.isfinite(est.stderr) and est.stderr >= 0 else None


#: Markers around the generated option tables in docs/analyze.md.
DOCS_BEGIN = "<!-- experiment options: generated by scripts/experiment_docs.py, do not edit -->"
DOCS_END = "<!-- end of the generated experiment options -->"


def options_markdown() -> str:
    """The option tables of every experiment, as docs/analyze.md shows them (Markdown)."""
    parts = []
    for name, exp in all_experiments().items():
        parts.append(f"### `{name}`: {exp.title or name}\n\n{exp.summary}. Input: {exp.inputs}. Reports: "
                     + ", ".join(f"`{p}`" for p in exp.reports) + f" ({exp.shaft}).\n")
        if not exp.options:
            parts.append("No options.\n")
            continue
        rows = ["| option | in words | unit | default | description |", "|---|---|---|---|---|"]
        for opt in exp.options:
            flag = ", ".join(f"`--{n}`" for n in (opt.name, *opt.aliases))
            if opt.required:
                flag += " (required)"
            unit = format_unit(opt.unit) if opt.unit else ("one of " + ", ".join(opt.choices) if opt.choices else "")
            default = "" if opt.default is None else f"{opt.default:g}" if isinstance(opt.default, float) else (
                str(opt.default))
            if opt.kind == "flag":
                default = ""
            text = opt.help.replace("|", "\\|")
            rows.append(f"| {flag} | {opt.label} | {unit} | {default} | {text} |")
        parts.append("\n".join(rows) + "\n")
    return "\n".join(parts)
