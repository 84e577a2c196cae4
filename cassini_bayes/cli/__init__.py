"""The ``cassini-bayes`` command.

Each sub-command lives in its own module of this package and exposes ``register(app, groups)``;
modules are discovered here, so adding a command never edits this file. ``groups["fit"]`` is the
``cassini-bayes fit`` group. ``ORDER`` (an int, default 100) sorts the commands in ``--help``.

Global options, given before the command (docs/cli.md): ``--jax-cache DIR|off`` moves or switches
off the compilation cache (:mod:`cassini_bayes._jax_cache`); ``--verbose`` prints its hits and
misses at the end. Before any command runs, :func:`cassini_bayes.setup_jax` sets JAX up (64-bit,
the cache, one CPU device per core); ``--help``, ``--version`` and usage errors import no JAX.

One error path (:func:`main`; docs/cli.md lists the exit codes): whatever goes wrong is at most a
usage line and one ``error:`` line on stderr, never a traceback (unless ``CASSINI_BAYES_DEBUG=1``).
Commands run inside :func:`cassini_bayes.errors.command_line`, so the library's messages name
options (``--method rcs``) rather than Python arguments (``method='rcs'``):

- 0 success; 2 a usage error (unknown command or option, a missing or out-of-range value; no
  arguments at all prints the help) or bad input (:class:`cassini_bayes.errors.InputError`);
- 3 a run that did not converge under ``--strict`` (its outputs are written);
- 1 an operating-system error (full disk, no permission: the line names the path) or an internal
  error (a bug: the line says how to see the traceback);
- 130 interrupted (Ctrl-C), 143 terminated (SIGTERM, handled as Ctrl-C): nothing half-written
  is left under the output's name, nor a temporary directory beside it.

The usage errors come from Click, which recent typer releases vendor as ``typer._click`` and older
ones took from the ``click`` package: they are recognised by class name, so any typer release
works.
"""

from __future__ import annotations

import contextlib
import errno
import importlib
import os
import pkgutil
import signal
import sys
import threading
import traceback
import warnings

import typer

from cassini_bayes import __version__, _jax_cache
from cassini_bayes._devices import setup_jax
from cassini_bayes.errors import InputError, Interrupted, NotConvergedError, command_line

app = typer.Typer(
    name="cassini-bayes",
    help="Bayesian in-flight calibration of a spacecraft: inertia tensor, thrusters, a wheel's "
         "spin axis (Cassini and any spacecraft model file).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
groups: dict[str, typer.Typer] = {
    "fit": typer.Typer(help="Fit a posterior: inertia, thrust, wheel-axis (rwa4: Cassini's RWA4).",
                       no_args_is_help=True),
}
app.add_typer(groups["fit"], name="fit")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"cassini-bayes {__version__}")
        raise typer.Exit()


_WITHOUT_JAX = frozenset({"report"})
"""Commands that read files and draw figures only: JAX's import (about 1 s) is not paid."""


@app.callback()
def _root(
    ctx: typer.Context,
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                 help="Print the version and exit."),
    jax_cache: str = typer.Option(None, "--jax-cache", metavar="DIR|off",
                                  help="Folder of JAX's compilation cache, or off (default: "
                                       f"${_jax_cache.ENV}, else ~/.cache/cassini-bayes/jax)."),
    verbose: bool = typer.Option(False, "--verbose", "-v",
                                 help="At the end, print on stderr what the run did with the "
                                      "compilation cache (hits, misses)."),
) -> None:
    """Bayesian in-flight calibration of a spacecraft: inertia tensor, thrusters, wheel axes."""
    if jax_cache is not None:
        os.environ[_jax_cache.ENV] = jax_cache  # worker processes (sbc --executor dask) follow
        _jax_cache.enable(jax_cache)
    # 64-bit, the cache, one CPU device per core (at least 4) so that the chains run in
    # parallel: before the command runs, hence before anything starts JAX's backend; a
    # command that computes nothing with JAX does not import it
    if ctx.invoked_subcommand not in _WITHOUT_JAX:
        setup_jax()
    if verbose:
        ctx.call_on_close(lambda: print(_jax_cache.stats().line(), file=sys.stderr))


def _register_all() -> None:
    mods = []
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        if hasattr(mod, "register"):
            mods.append(mod)
    for mod in sorted(mods, key=lambda m: (getattr(m, "ORDER", 100), m.__name__)):
        mod.register(app, groups)


_register_all()


_DEBUG_ENV = "CASSINI_BAYES_DEBUG"


def _click_kind(e: BaseException) -> str | None:
    """``"Exit"``, ``"Abort"``, ``"NoArgsIsHelpError"``, ``"UsageError"`` or ``"ClickException"``
    for an exception of Click (``click`` or ``typer._click``) or typer, else None."""
    names = [c.__name__ for c in type(e).__mro__
             if c.__module__.split(".")[0] in ("click", "typer")]
    for kind in ("Exit", "Abort", "NoArgsIsHelpError", "UsageError", "ClickException"):
        if kind in names:
            return kind
    return None


def _err(line: str) -> None:
    print(" ".join(line.split()), file=sys.stderr)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Python warnings as one ``warning:`` line each (no source line)."""
    print(f"warning: {' '.join(str(message).split())}", file=file or sys.stderr)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where Ctrl-C raises KeyboardInterrupt: every clean-up that Ctrl-C runs
    (temporary run directories, SBC checkpoints) runs for it too."""


_SIGNAL_EXIT = {signal.SIGINT: (130, "interrupted"), signal.SIGTERM: (143, "terminated")}


@contextlib.contextmanager
def _sigterm_as_ctrl_c(received: list[int]):
    """Inside the block SIGTERM raises :class:`Terminated` (Python's default ends the process at
    once, leaving a half-written temporary run directory); ``received`` gets the signal, so the
    exit status says which one stopped the run (docs/cli.md: 143 = 128 + SIGTERM)."""
    if threading.current_thread() is not threading.main_thread():
        yield   # (signal handlers can only be set from the main thread)
        return

    def handler(signum, frame) -> None:
        received.append(signum)
        raise Terminated

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def _ctrl_c_never_lost():
    """Deliver Ctrl-C (or SIGTERM) again when Python swallowed it.

    A KeyboardInterrupt raised while a garbage-collector callback (JAX registers one) or a
    ``__del__`` runs cannot propagate: Python reports it as "Exception ignored" and the run goes
    on as if no key was pressed. Such a swallowed interrupt reaches ``sys.unraisablehook``; this
    sends SIGINT to the process again a moment later, when it can land.
    """
    previous = sys.unraisablehook

    def hook(unraisable) -> None:
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            again = signal.SIGTERM if issubclass(unraisable.exc_type, Terminated) else \
                signal.SIGINT
            timer = threading.Timer(0.05, os.kill, (os.getpid(), again))
            timer.daemon = True
            timer.start()
            return
        previous(unraisable)

    sys.unraisablehook = hook
    try:
        yield
    finally:
        sys.unraisablehook = previous


def _usage_error(e: Exception) -> int:
    """Print a Click usage error as the command's usage line plus one error line."""
    ctx = getattr(e, "ctx", None)
    command = getattr(ctx, "command_path", None) or "cassini-bayes"
    if ctx is not None:
        try:
            print(ctx.get_usage(), file=sys.stderr)
        except Exception:  # noqa: BLE001 - the usage line is a courtesy
            pass
    try:
        msg = e.format_message()
    except Exception:  # noqa: BLE001
        msg = str(e)
    _err(f"error: {msg.rstrip('.')}. Try '{command} --help'.")
    return 2


def _os_error(e: OSError) -> int:
    if e.errno == errno.EPIPE:  # stdout closed by the reader (`| head`): stop quietly
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    where = ": ".join(str(f) for f in (e.filename, e.filename2) if f is not None)
    reason = e.strerror or str(e)
    _err(f"error: {where + ': ' if where else ''}{reason}"
         + (" (free some space and run again)" if e.errno == errno.ENOSPC else ""))
    return 1


def main(argv: list[str] | None = None) -> int:
    """Run ``cassini-bayes ARGV`` (default ``sys.argv[1:]``); returns the exit status.

    Never raises and never prints a traceback (module docstring), except with
    ``CASSINI_BAYES_DEBUG=1`` set for an internal error.
    """
    args = sys.argv[1:] if argv is None else [str(a) for a in argv]
    if not args:  # the help, as a usage error (Click >= 8.2 does so for groups too)
        main(["--help"])
        return 2
    received: list[int] = []

    def stopped(what: str = "") -> int:
        """The exit status and line of a run stopped by Ctrl-C (130) or SIGTERM (143)."""
        code, word = _SIGNAL_EXIT[signal.SIGTERM if signal.SIGTERM in received
                                  else signal.SIGINT]
        _err(f"{word}: {what}" if what else word)
        return code

    try:
        with (warnings.catch_warnings(), _sigterm_as_ctrl_c(received), _ctrl_c_never_lost(),
              command_line()):
            warnings.showwarning = _show_warning
            rv = app(args=args, prog_name="cassini-bayes", standalone_mode=False)
    except InputError as e:
        _err(f"error: {e}")
        return 2
    except NotConvergedError as e:
        _err(f"error: {e}")
        return 3
    except Interrupted as e:
        return stopped(str(e))
    except KeyboardInterrupt:
        return stopped()
    except OSError as e:
        return _os_error(e)
    except SystemExit as e:  # Click's own exit on a closed pipe
        return e.code if isinstance(e.code, int) else 1
    except Exception as e:  # noqa: BLE001 - the one place every other error ends
        kind = _click_kind(e)
        if kind == "Exit":
            return int(getattr(e, "exit_code", 0) or 0)
        if kind == "Abort":  # older Click turns Ctrl-C (and end of input) into Abort
            if isinstance(e.__context__, KeyboardInterrupt):
                return stopped()
            _err("error: aborted")
            return 1
        if kind == "NoArgsIsHelpError":  # a group given no command: its help (rich prints it)
            if e.format_message().strip():
                print(e.format_message(), file=sys.stderr)
            return 2
        if kind == "UsageError":
            return _usage_error(e)
        if kind == "ClickException":
            _err(f"error: {e.format_message()}")
            return int(getattr(e, "exit_code", 1))
        if isinstance(e, UnicodeDecodeError):
            _err(f"error: an input file is not UTF-8 text ({e}); check the file arguments")
            return 2
        if os.environ.get(_DEBUG_ENV):
            traceback.print_exc()
        _err(f"error: internal error ({type(e).__name__}): {e}")
        _err(f"(a bug in cassini-bayes: rerun with {_DEBUG_ENV}=1 for the traceback)")
        return 1
    if rv == 130:  # recent typer turns Ctrl-C into a returned 130 (no command returns 130)
        return stopped()
    return rv if isinstance(rv, int) and not isinstance(rv, bool) else 0


def _hide_dask(argv: list[str]) -> None:
    """Make Dask unimportable for a command that does not ask for it (``--executor dask``).

    xarray imports ``dask.array`` at its first variable and ``distributed`` when it writes a
    netCDF file where Dask is installed, a cost paid by every fit that never uses it. Only the
    console script does this; :func:`main` called in-process leaves the interpreter alone.
    """
    asked = "--executor=dask" in argv or any(
        a == "--executor" and b == "dask" for a, b in zip(argv, argv[1:]))
    if "dask" not in sys.modules and not asked:
        sys.modules["dask"] = None  # type: ignore[assignment]  # find_spec then says: absent


def entry() -> None:
    """The console script: :func:`main` on ``sys.argv``, then end the process.

    After an interrupt (Ctrl-C or SIGTERM) the process ends with ``os._exit(130)`` (``143``)
    once stdout and stderr are flushed: JAX's threads can still be running then, and the
    interpreter's normal shutdown can crash (segfault) under them. Everything the run writes is
    already cleaned up by then.
    """
    _hide_dask(sys.argv[1:])
    code = main()
    if code in (130, 143):
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    entry()
