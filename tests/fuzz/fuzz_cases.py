"""Make fuzz cases from the corpus: a valid run with its files, options or environment mutated."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from functools import cache
from pathlib import Path

from fuzz_corpus import Seed
from fuzz_harness import Case
from fuzz_mutate import SPECIAL_FILES, Chooser, mutate_options, mutators_for

#: Values of MOTORLAB_MAX_INPUT_SIZE a user might set.
SIZE_VALUES = ("9**9**9", "2**1024 B", "1e999", "-1", "0", "abc", "2 GB", "1 kB", "100", "1e-300 GB", "nan",
               "9" * 5000, "5 furlongs")

#: How a case is made, with weights (a name repeated weighs more).
MODES = ("file", "file", "file", "file", "special", "options", "options", "file+options", "env", "valid")


@cache
def known_options(command: tuple[str, ...]) -> tuple[str, ...]:
    """The long options of ``motorlab *command`` (from the CLI's own parser), help and version excluded."""
    from motorlab import cli

    parser: argparse.ArgumentParser = cli.build_parser()
    for word in command:
        sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
        if sub is None:  # a positional word (tune velocity), not a sub-command
            break
        parser = sub.choices[word]
    names = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            continue
        longs = [o for o in action.option_strings if o.startswith("--") and o not in ("--help", "--version")]
        if longs:
            names.append(longs[0])
    return tuple(names)


def _read(corpus: Path, name: str) -> bytes:
    return (corpus / name).read_bytes()


def make_case(seed: Seed, corpus: Path, c: Chooser, *, modes: Sequence[str] = MODES) -> Case:
    """One case of ``seed``: the mode (file, special file, options, environment, valid) chosen by ``c``."""
    mode = c.choice(list(modes))
    files = {name: _read(corpus, name) for name in (*seed.files, *seed.support)}
    options = list(seed.options)
    outputs = [options[k + 1] for k, o in enumerate(options[:-1]) if o in ("-o", "--output")]
    case = Case(seed=seed.name, mutation=mode, argv=[], files=files, json_output=seed.json_output,
                session="session" in seed.tags, any_outcome="any-outcome" in seed.tags)
    if case.session:  # what a session's file list may point at
        case.special.update({"fifo.csv": "fifo", "loop.csv": "symlink-loop", "zero.csv": "dev-zero"})
    inputs = list(seed.files) or list(seed.support)  # tune's --params file is its input
    if mode == "valid":
        case.valid = not seed.real
    if mode in ("file", "file+options") and inputs:
        name = c.choice(inputs) if not case.session else c.choice([*inputs, *seed.support])
        table = mutators_for(seed.kind if name in seed.files or not seed.files else "text")
        steps = []
        for _ in range(c.choice([1, 1, 2])):
            mutator = c.choice(sorted(table))
            files[name] = table[mutator](files[name], c)
            steps.append(mutator)
        case.blame = name if name in seed.files or not case.session else None
        case.mutation = f"{name}: {' + '.join(steps)}"
    if mode == "special" and (inputs or seed.support):
        name = c.choice([*inputs, *seed.support])
        kind = c.choice(list(SPECIAL_FILES))
        del files[name]
        case.special[name] = kind
        case.blame = name if name in inputs else None
        case.mutation = f"{name}: {kind}"
    if mode in ("options", "file+options") or (mode in ("file", "special") and not inputs):
        options, what = mutate_options(options, known_options(seed.command), c)
        case.mutation = f"{case.mutation}; {what}" if mode == "file+options" else what
        if mode == "file+options":
            case.blame = None  # either may be refused first
        outputs += [options[k + 1] for k, o in enumerate(options[:-1]) if o in ("-o", "--output", "--plot")]
        outputs += [o.split("=", 1)[1] for o in options if o.startswith(("--output=", "--plot=", "--emit="))]
    if mode == "env":
        value = c.choice(list(SIZE_VALUES))
        case.env["MOTORLAB_MAX_INPUT_SIZE"] = value
        case.mutation = f"MOTORLAB_MAX_INPUT_SIZE={value!r}"
    if "--plot" in seed.outputs and mode == "valid" and c.choice([False, True]):
        options += ["--plot", "fit.png"]
        outputs.append("fit.png")
    argv = [*seed.command, *seed.files, *options]
    if seed.json_output and "--json" not in argv:
        argv.append("--json")
    case.argv = argv
    if "writes-truth" in seed.tags:  # simulate writes truth.json beside its output (documented)
        outputs += [str(Path(o).parent / "truth.json") if Path(o).parent != Path() else "truth.json" for o in outputs]
    case.outputs = sorted(set(outputs))
    return case


def case_for(index: int, run_seed: int, seeds: Sequence[Seed], corpus: Path) -> Case:
    """Case ``index`` of the run with seed ``run_seed``: the same every time (resumable, reproducible)."""
    from fuzz_mutate import RandomChooser

    c = RandomChooser(f"{run_seed}:{index}")
    return make_case(pick_seed(seeds, c), corpus, c)


def pick_seed(seeds: Sequence[Seed], c: Chooser) -> Seed:
    """A seed: each quick rig-made one as likely as the real SysId logs together, the real dyno tables together,
    and a third of the slow whole-model fits (which take seconds a case)."""
    rig = [s for s in seeds if not s.real and not s.slow]
    slow = [s for s in seeds if not s.real and s.slow]  # the whole-model fits: seconds a case
    real = [s for s in seeds if s.real and "any-outcome" not in s.tags]
    tables = [s for s in seeds if "any-outcome" in s.tags]
    groups = [[s] for s in rig] + [g for g in (slow, slow, slow, real, tables) if g]
    return c.choice(c.choice(groups))
