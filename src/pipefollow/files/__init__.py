"""Files: atomic writes, the reader of the user's text files, and checks of output paths.

Also ``paper_training``: the paper's number of training episodes and their length, the defaults
every layer and the command line's help texts read.

The bottom of the package: it imports nothing of pipefollow, and every layer may import it.
"""
