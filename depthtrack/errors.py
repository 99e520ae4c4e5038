"""The one exception type that means "the user's input is wrong".

The CLI turns it into a single line on stderr and exit status 2; library callers
can catch it like any ``ValueError``.
"""
from __future__ import annotations

import os


class InputError(ValueError):
    """Bad user input: a file that is missing, malformed or inconsistent.

    Parameters
    ----------
    path : str or os.PathLike or None
        The file (or directory) at fault; ``None`` when no file is involved.
    problem : str
        What is wrong, in words a user understands.
    """

    def __init__(self, path, problem: str):
        self.path = None if path is None else os.fspath(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}" if self.path else problem)
