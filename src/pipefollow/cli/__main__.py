"""``python -m pipefollow.cli``."""

from pipefollow.cli import main

if __name__ == "__main__":  # pragma: no cover
    main()
