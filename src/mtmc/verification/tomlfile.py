"""Reading the TOML study files of a verification: one place for the file and parse errors.

Examples
--------
>>> top = parse_study('machine = "XFYZ"', "s.toml")
>>> top.text("machine")
'XFYZ'
>>> parse_study("machine = 1.2.3", "s.toml")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
mtmc.errors.ParseError: s.toml:1:14: not valid TOML: Expected newline or end of document...
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from mtmc.errors import InputError, ParseError
from mtmc.study.spec import Fields, Source

__all__ = ["parse_study", "read_study_file"]


def read_study_file(path: str | Path) -> str:
    """The text of a study file.

    Raises
    ------
    InputError
        If the file cannot be read or is not UTF-8 text (naming the file).
    """
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(
            f"cannot read the study file: {exc.strerror or exc}", file=str(path)
        ) from None
    except UnicodeDecodeError:
        raise InputError("the study file is not UTF-8 text", file=str(path)) from None


def parse_study(text: str, file: str = "<study>", folder: Path | None = None) -> Fields:
    """The top table of a study's TOML text, with the source for line numbers.

    Raises
    ------
    ParseError
        If the text is not TOML (with the line and column).
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        msg = str(exc).split(" (at line")[0]
        line, col = (int(m.group(1)), int(m.group(2))) if m else (None, None)
        raise ParseError(f"not valid TOML: {msg}", file=file, line=line, column=col) from None
    return Fields(Source.from_text(text, file, folder), data)
