"""The ``cassini-bayes`` command.

Each sub-command lives in its own module of this package and exposes ``register(app, groups)``;
modules are discovered here, so adding a command never edits this file. ``groups["fit"]`` is the
``cassini-bayes fit`` group. ``ORDER`` (an int, default 100) sorts the commands in ``--help``.

User errors (:class:`cassini_bayes.errors.InputError`) are printed as one line on stderr with exit
status 2; a run that did not converge under ``--strict`` exits 3. No traceback is ever shown for
either.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import typer

from cassini_bayes import __version__
from cassini_bayes.errors import InputError, NotConvergedError

app = typer.Typer(
    name="cassini-bayes",
    help="Bayesian in-flight calibration of Cassini: inertia tensor, thrusters, RWA4 spin axis.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
groups: dict[str, typer.Typer] = {
    "fit": typer.Typer(help="Fit a posterior: inertia, thrust or rwa4.", no_args_is_help=True),
}
app.add_typer(groups["fit"], name="fit")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"cassini-bayes {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                 help="Print the version and exit."),
) -> None:
    """Bayesian in-flight calibration of Cassini: inertia tensor, thrusters, RWA4 spin axis."""


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


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script: run the app, turning user errors into one line."""
    try:
        app(args=argv, prog_name="cassini-bayes", standalone_mode=False)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except NotConvergedError as e:
        print(f"error: {e}", file=sys.stderr)
        return 3
    except typer.Exit as e:
        return e.exit_code
    except typer.Abort:
        print("aborted", file=sys.stderr)
        return 130
    except Exception as e:  # click usage errors
        import click

        if isinstance(e, click.exceptions.ClickException):
            e.show()
            return e.exit_code
        if isinstance(e, click.exceptions.Exit):
            return e.exit_code
        raise
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
