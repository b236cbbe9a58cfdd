"""Path strings and user text quoted back to the terminal.

A path given on the command line or in a design file is refused before the operating system sees it when it
is empty, holds a NUL byte (which no file name can hold; Python would raise ``ValueError``) or holds another
control character (a file name with a line break or an escape sequence is almost surely a mistake, and quoting
it would break the one-line error).  :func:`printable` escapes control characters the way ``repr`` does, for
every message that quotes a user's key, value or path.
"""

from __future__ import annotations

import os
import re

_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def printable(text: str) -> str:
    """``text`` with every control character (C0, DEL, C1, U+2028/U+2029) written as its escape
    (``\\x07``, ``\\n``, ``\\u2028``), so quoting it prints one line and rings no bell.

    >>> printable("a\\x07b\\nc")
    'a\\\\x07b\\\\nc'
    """
    return _CONTROL.sub(lambda m: repr(m.group())[1:-1], text)


def path_problem(path: str | os.PathLike) -> str | None:
    """Why ``path`` cannot name a file (``"is empty"``, ``"holds a NUL byte …"``, ``"holds the control character
    …"``: the caller names the path), or ``None`` when it can."""
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = text.decode("utf-8", errors="surrogateescape")
    if text == "":
        return "is empty"
    if "\x00" in text:
        return "holds a NUL byte, which no file name can hold"
    m = _CONTROL.search(text)
    if m:
        return f"holds the control character {repr(m.group())[1:-1]}"
    return None
