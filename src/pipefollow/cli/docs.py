"""``pipefollow docs``: the documentation site's generated pages."""

from __future__ import annotations

from pathlib import Path

import click

from pipefollow.cli.common import UserError, guard


@click.group()
def docs() -> None:
    """The documentation site's generated pages: results pages rendered from the stored outputs."""


@docs.command()
@click.option(
    "--docs",
    "docs_dir",
    default="docs",
    show_default=True,
    type=click.Path(file_okay=False),
    help="The documentation folder whose stored outputs (reproduction/, readings/, vision/, ...) are read.",
)
@click.option(
    "--out",
    "out_dir",
    default=None,
    type=click.Path(file_okay=False),
    help="Folder the pages are written to [default: DOCS/results, the committed pages: the one "
    "command whose default output is inside docs/, since regenerating them is its purpose].",
)
@click.option(
    "--page",
    "names",
    multiple=True,
    metavar="NAME",
    help="Only this page (repeatable): reproduction, readings, reference-learners, generalization, "
    "deep-vs-paper, robustness, sample-efficiency, perception, speed [default: all].",
)
@click.option(
    "--readme",
    "readme_path",
    default=None,
    type=click.Path(dir_okay=False),
    help="The README whose claims table and compile time are regenerated too (between their marker lines) "
    "[default: README.md beside DOCS, if there is one].",
)
@click.option(
    "--check",
    is_flag=True,
    help="Write nothing; list the pages that differ from what the stored outputs give "
    "and exit with status 1 if any.",
)
@guard
def results(docs_dir, out_dir, names, readme_path, check):
    """Write one results page per result from the stored outputs under DOCS.

    Tables are rendered from the stored CSV/JSON files and every number in a page's text is filled
    from them; so are the generated blocks of guide pages (a command's sample output, a table of
    results) between their marker lines, rewritten in place. The output depends on the stored
    outputs only (no clock or machine of its own: the dates and machines a page shows are those its
    outputs record), so a page that differs from its regeneration is stale (--check;
    tests/test_results_pages.py).
    """
    from pipefollow.experiments import results_pages
    from pipefollow.experiments.results_pages import blocks

    for n in names:
        if n not in results_pages.PAGES:
            raise click.BadParameter(
                f"unknown page {n!r} (choose from {', '.join(results_pages.PAGES)})", param_hint="--page"
            )
    if not Path(docs_dir).is_dir():
        raise UserError(f"--docs '{docs_dir}': no such folder")
    from pipefollow.experiments.results_pages import readme

    out = Path(out_dir) if out_dir else Path(docs_dir) / "results"
    if readme_path is None and (Path(docs_dir).resolve().parent / "README.md").is_file():
        readme_path = Path(docs_dir).resolve().parent / "README.md"
    if readme_path is not None and not Path(readme_path).is_file():
        raise UserError(f"--readme '{readme_path}': no such file")
    if check:
        stale = results_pages.stale_pages(docs_dir, out, names or None)
        for n in stale:
            click.echo(f"stale: {out / (n + '.md')}")
        if readme_path is not None and readme.stale(Path(readme_path), Path(docs_dir)):
            stale.append("README")
            click.echo(f"stale: the generated blocks (claims table, compile time) of {readme_path}")
        for path in blocks.stale(Path(docs_dir)):
            stale.append(str(path))
            click.echo(f"stale: the generated blocks (sample outputs, tables) of {path}")
        if stale:
            raise SystemExit(1)
        click.echo(
            f"up to date: {len(names or results_pages.PAGES)} page(s) in {out}, the generated blocks of "
            f"{len(blocks.pages(Path(docs_dir)))} guide page(s)"
        )
        return
    for path in results_pages.write_pages(docs_dir, out, names or None):
        click.echo(f"wrote {path}")
    if readme_path is not None and readme.update(Path(readme_path), Path(docs_dir)):
        click.echo(f"wrote the generated blocks (claims table, compile time) of {readme_path}")
    for path in blocks.update(Path(docs_dir)):
        click.echo(f"wrote the generated blocks (sample outputs, tables) of {path}")
