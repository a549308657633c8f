"""Graph files a hostile hand wrote, and what the graph writer writes read back.

References: the reader's own contract (a :class:`GraphError` naming file, line and
field for every malformed entry) and the writer's (``loads_graph(dumps_graph(g)) == g``
for every title and name, whatever characters they hold).
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc.document import loads_toml
from mtmc.errors import GraphError, MtmcError
from mtmc.graph import check_graph, loads_graph
from mtmc.graph.toml_format import dumps_graph, toml_string

PLACE = '{name = "a", type = "real", value = 1.0}'
TRANS = '{name = "t", op = "displace", in = ["a", "a"], out = "b"}'


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (f"place = [{PLACE}, false]", "place #2: expected a table"),
        (f"place = [{PLACE}, 3]", "place #2: expected a table"),
        (f'place = [{PLACE}, "x"]', "place #2: expected a table"),
        (f"place = [{PLACE}, [1]]", "place #2: expected a table"),
        (f"place = [{PLACE}]\ntransition = [{TRANS}, false]", "transition #2: expected"),
        (f"place = [{PLACE}]\ntransition = [1.5, {TRANS}]", "transition #1: expected"),
    ],
)
def test_a_scalar_in_an_inline_array_of_tables_is_a_located_error(text: str, words: str) -> None:
    with pytest.raises(GraphError, match=words) as info:
        loads_graph(text, file="g.toml")
    line = text.count("\n") + 1  # the array's own line: the last of the text
    assert str(info.value).startswith(f"g.toml:{line}: field ")


def test_a_chain_of_1000_displacements_is_checked_without_recursion() -> None:
    lines = ['[[place]]\nname = "p0"\ntype = "real"\nvalue = 1.0']
    for i in range(1000):
        lines.append(
            f'[[transition]]\nname = "t{i}"\nop = "displace"\nin = ["p{i}", "p{i}"]\n'
            f'out = "p{i + 1}"'
        )
    g = loads_graph("\n".join(lines), file="chain.toml")
    check_graph(g)
    assert len(g.transitions) == 1000


def test_the_dimensions_of_a_chain_are_found_in_linear_time(monkeypatch) -> None:
    # every place of a chain of n displacements asked in turn (as reading the graph does):
    # each link's rule is looked up a bounded number of times, not once per place above it
    # (n²/2 = 500,000 lookups at n = 1000 took a minute). Reference: the count of lookups.
    from mtmc.graph import units

    n = 1000
    lines = ['[[place]]\nname = "p0"\ntype = "real"\nvalue = 1.0\nunit = "deg"']
    for i in range(n):
        lines.append(
            f'[[transition]]\nname = "t{i}"\nop = "displace"\nin = ["p{i}", "p{i}"]\n'
            f'out = "p{i + 1}"'
        )
    plan = check_graph(loads_graph("\n".join(lines), file="chain.toml"))
    calls = 0
    rule = units._rule

    def counted(plan_, name):
        nonlocal calls
        calls += 1
        return rule(plan_, name)

    monkeypatch.setattr(units, "_rule", counted)
    plan.dimensions.clear()
    dims = [units.place_dimension(plan, f"p{i}") for i in range(n, -1, -1)]
    assert dims == [(0, 1)] * (n + 1)  # an angle all the way down
    assert calls <= 2 * (n + 1)


NAMES = st.text(min_size=1, max_size=12)


@settings(max_examples=300, deadline=None)
@given(title=st.text(max_size=30), name=NAMES)
def test_everything_the_writer_writes_its_reader_reads(title: str, name: str) -> None:
    """Titles and names of any Unicode (controls, DEL, astral planes) round-trip."""
    text = f"title = {toml_string(title)}\n[[place]]\nname = {toml_string(name)}\n"
    text += 'type = "real"\nvalue = 1.0\n'
    try:
        g = loads_graph(text, file="g.toml")
    except MtmcError:
        return  # a name the graph refuses (the reader said so); the strings themselves read
    again = loads_graph(dumps_graph(g), file="g.toml")
    assert again.title == title
    assert again.places[0].name == name


@settings(max_examples=300, deadline=None)
@given(s=st.text())
def test_a_toml_string_reads_back_as_itself(s: str) -> None:
    assert loads_toml(f"k = {toml_string(s)}\n", "k.toml").data["k"] == s
