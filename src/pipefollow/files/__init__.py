"""Files: atomic writes, the reader of the user's text files, and checks of output paths.

The bottom of the package: it imports nothing of pipefollow, and every layer may import it.
"""
