"""The line of each key of a TOML text: brackets and quotes inside strings and comments.

``key_lines`` scans the text (``tomllib`` gives no lines). A bracket in a string or a
comment must not open an array, and the lines of a multi-line string must not be read as
keys or headers: otherwise every later key loses its line, and an error points at the
wrong line of the user's file.
"""

from __future__ import annotations

import tomllib

import pytest

from mtmc.document import key_lines
from mtmc.errors import MtmcError
from mtmc.study import loads_study

TEXT = "\n".join(
    [
        'a = ["x[", "y"]',
        "b = 1",
        'c = """',
        "[fake]",
        "k = 2",
        '"""',
        "d = [  # [",
        '  1, "]",',
        "]",
        "e = 3",
        "f = '''[",
        "'''",
        'g = "q\\"[" # [',
        "h = 4",
        "[t]",
        'i = {x = "[", y = 2}',
        "j = 5",
        "l = 'C:\\path\\[' # a literal string keeps its backslash",
        "m = 6",
    ]
)


def test_the_text_is_valid_toml() -> None:
    doc = tomllib.loads(TEXT)
    assert doc["c"] == "[fake]\nk = 2\n"
    assert doc["t"]["m"] == 6


def test_each_key_is_on_its_own_line() -> None:
    expected = {
        **{(k,): n for k, n in (("a", 1), ("b", 2), ("c", 3), ("d", 7), ("e", 10))},
        **{(k,): n for k, n in (("f", 11), ("g", 13), ("h", 14), ("t", 15))},
        **{("t", k): n for k, n in (("i", 16), ("j", 17), ("l", 18), ("m", 19))},
    }
    assert key_lines(TEXT) == expected  # no [fake] or k = 2 from inside the string


@pytest.mark.parametrize(
    "before",
    [
        'title = "a [b"',
        'title = "a [b" # ]',
        "title = 'a [b'",
        'title = """a\n[b\n"""',
        'title = "x" # [',
        'unit = "mm"  # [[',
    ],
)
def test_an_error_after_a_bracket_in_a_string_names_its_own_line(before: str) -> None:
    text = f'kind = "propagate"\n{before}\nmodel = "a + b"\n[inputs]\na = 1\nb = "normal(0, x)"\n'
    line = text.splitlines().index('b = "normal(0, x)"') + 1
    with pytest.raises(MtmcError) as err:
        loads_study(text, file="s.toml")
    assert f"s.toml:{line}:" in str(err.value)
