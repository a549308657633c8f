import pickle

import pytest

from mtmc import errors


@pytest.mark.parametrize(
    ("cls", "builtin"),
    [
        (errors.InputError, ValueError),
        (errors.ParseError, ValueError),
        (errors.DistributionError, ValueError),
        (errors.ExpressionError, ValueError),
        (errors.DegenerateGeometryError, ValueError),
        (errors.GraphError, ValueError),
        (errors.TopologyError, ValueError),
        (errors.ConvergenceError, RuntimeError),
    ],
)
def test_each_error_is_also_the_builtin_and_pickles_with_its_fields(cls, builtin):
    err = cls("expected three points", file="g.toml", line=7, column=3, field="in")
    assert isinstance(err, builtin)
    assert isinstance(err, errors.MtmcError)
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is cls
    assert (back.file, back.line, back.column, back.field) == ("g.toml", 7, 3, "in")
    assert str(back) == str(err) == "g.toml:7:3: field in: expected three points"


def test_message_without_file_names_line_and_field():
    assert str(errors.ParseError("bad token", line=2, column=5)) == "line 2, column 5: bad token"
    assert str(errors.InputError("must be > 0", field="trials")) == "field trials: must be > 0"
    assert str(errors.MtmcError("plain")) == "plain"
