"""One analysis per experiment of the seeds; every one returns a :class:`~motorlab.results.FitResult`.

Each module provides the library function named after its experiment (``spindown(recording, *,
cpr=, inertia=, ...)``). How each experiment's files are read, its options and what it reports are
described in :mod:`motorlab.experiments` (one module per experiment), from which the CLI, the
notebook API and sessions are generated.
"""
