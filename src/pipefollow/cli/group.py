"""The ``pipefollow`` group: commands known by name, their modules imported only when they run.

Click's "Lazily Loading Subcommands" recipe (its ``LazyGroup``), as pip keeps its
``commands_dict`` of module paths: :data:`pipefollow.cli.COMMANDS` maps each command's name to
``"module:attribute"``, so ``pipefollow --help`` imports click alone and ``pipefollow benchmark``
imports what the benchmark needs and nothing of the other commands. A command's short help in
the listing comes from the same table, so listing them imports none.

This module imports only click and the standard library.
"""

from __future__ import annotations

import importlib
import sys

import click

from pipefollow import __version__


class UserError(click.ClickException):
    """A one-line error about the user's input, exit status 2."""

    exit_code = 2

    def show(self, file=None) -> None:  # noqa: D102
        click.echo(f"pipefollow: error: {self.message}", err=True)


# click ≥ 8.2 raises this for a bare group; older versions print the help and exit 0 themselves
_NO_ARGS_IS_HELP = getattr(click.exceptions, "NoArgsIsHelpError", ())


class LazyGroup(click.Group):
    """A group whose commands are ``name → (import path, short help)`` until one is run."""

    def __init__(self, *args, lazy_commands: dict[str, tuple[str, str]] | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.lazy_commands: dict[str, tuple[str, str]] = dict(lazy_commands or {})

    def add_lazy_command(self, name: str, import_path: str, short_help: str) -> None:
        """Know command ``name`` as ``"module:attribute"``, listed with ``short_help``."""
        self.lazy_commands[name] = (import_path, short_help)

    def list_commands(self, ctx: click.Context) -> list[str]:  # noqa: D102
        return sorted(set(super().list_commands(ctx)) | set(self.lazy_commands))

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:  # noqa: D102
        if cmd_name in self.lazy_commands and cmd_name not in self.commands:
            self.commands[cmd_name] = self._load(cmd_name)
        return super().get_command(ctx, cmd_name)

    def _load(self, cmd_name: str) -> click.Command:
        modname, attr = self.lazy_commands[cmd_name][0].split(":")
        command = getattr(importlib.import_module(modname), attr)
        if not isinstance(command, click.Command):
            raise TypeError(f"{modname}:{attr} is not a click command")
        return command

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The listing of ``--help``, with the lazy commands' help from the table (no import)."""
        rows = []
        for name in self.list_commands(ctx):
            if name in self.commands:
                cmd = self.commands[name]
                if cmd.hidden:
                    continue
                text = cmd.get_short_help_str(formatter.width - 6 - len(name))
            else:
                text = self.lazy_commands[name][1]
            rows.append((name, text))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


class OneLineErrors(LazyGroup):
    """Click's own usage errors (a bad option value, a missing option) on one line, exit 2."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):  # noqa: D102
        self.invocation = list(sys.argv[1:] if args is None else args)  # for provenance records
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.Abort:  # Ctrl-C: the shell's convention, 128 + SIGINT
            click.echo("pipefollow: interrupted", err=True)
            sys.exit(130)
        except _NO_ARGS_IS_HELP as e:  # the bare command asks for help; it is not an error
            click.echo(e.ctx.get_help() if e.ctx else self.get_help(click.Context(self)))
            sys.exit(0)
        except click.ClickException as e:
            if isinstance(e, UserError):
                e.show()
            else:
                click.echo(f"pipefollow: error: {e.format_message()}", err=True)
            sys.exit(e.exit_code)
        sys.exit(rv if isinstance(rv, int) else 0)


@click.group(
    cls=OneLineErrors,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.version_option(version=__version__, prog_name="pipefollow")
def main() -> None:
    """Learn and evaluate AUV pipeline-following controllers (Fjerdingen et al., 2010)."""
