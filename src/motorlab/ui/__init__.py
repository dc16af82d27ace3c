"""``motorlab ui``: a local browser app on the same CLI the terminal uses (see docs/ui.md).

:mod:`~motorlab.ui.schema` reads the forms off the CLI's argparse parsers, :mod:`~motorlab.ui.runner`
runs the CLI itself in a child process with a time limit, :mod:`~motorlab.ui.app` serves the page and
the HTTP API, and :mod:`~motorlab.ui.worker` is what the child process runs for the page's plots.
"""
