"""The campar command called in this process, as a test that checks what a command prints
(and no process boundary: exit on a signal, start-up, imports) calls it."""

import subprocess


def call_campar(capsys, *args) -> subprocess.CompletedProcess:
    """``campar ARGS`` through ``campar.cli.main`` in this process: its exit code and what
    it printed (``capsys``'s capture), as ``subprocess.run`` would return them."""
    from campar.cli import main

    argv = [str(a) for a in args]
    capsys.readouterr()  # what the test printed before is not the command's
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's refusals (exit 2) and --help (0)
        code = exc.code if isinstance(exc.code, int) else 1
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(["campar", *argv], code, out, err)
