"""The campar command called in this process, as a test that checks what a command prints
(and no process boundary: exit on a signal, start-up, imports) calls it."""

import contextlib
import io
import subprocess


def _exit_code(argv: list[str]) -> int:
    from campar.cli import main

    try:
        return main(argv)
    except SystemExit as exc:  # argparse's refusals (exit 2) and --help (0)
        return exc.code if isinstance(exc.code, int) else 1


def call_campar(capsys, *args) -> subprocess.CompletedProcess:
    """``campar ARGS`` through ``campar.cli.main`` in this process: its exit code and what
    it printed, as ``subprocess.run`` would return them. ``capsys``: the test's capture
    fixture, or None (a module-scoped fixture's call: sys.stdout and sys.stderr are
    redirected around it)."""
    argv = [str(a) for a in args]
    if capsys is not None:
        capsys.readouterr()  # what the test printed before is not the command's
        code = _exit_code(argv)
        printed, said = capsys.readouterr()
    else:
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = _exit_code(argv)
        printed, said = out.getvalue(), err.getvalue()
    return subprocess.CompletedProcess(["campar", *argv], code, printed, said)
