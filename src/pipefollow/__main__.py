"""``python -m pipefollow``: the ``pipefollow`` command without its console script."""

from pipefollow.cli import main

if __name__ == "__main__":  # pragma: no cover
    main(prog_name="pipefollow")
