import numpy as np
import pytest

from tippedisk_analysis import ParameterError
from tippedisk_analysis.ranges import parse_range, range_values


@pytest.mark.parametrize("text, expected", [("10:80:64", (10.0, 80.0, 64)), ("-50:-10:5", (-50.0, -10.0, 5)),
                                            ("0.1:0.1:1", (0.1, 0.1, 1)), ("0.3", (0.3, 0.3, 1))])
def test_parse_range(text, expected):
    assert parse_range(text, "omega") == expected


def test_range_values_include_both_ends():
    np.testing.assert_allclose(range_values("0:10:6", "omega"), [0, 2, 4, 6, 8, 10])
    np.testing.assert_allclose(range_values("0.3", "mu"), [0.3])


@pytest.mark.parametrize("text", ["10:80", "10:80:0", "a:b:3", "1:2:2.5", "1:nan:3", "0:inf:3", "1:2:1", "3:3:4",
                                  "1:2:3:4", ""])
def test_malformed_ranges_name_the_option_and_the_fix(text):
    with pytest.raises(ParameterError, match="--eps") as info:
        parse_range(text, "eps")
    assert "give" in str(info.value) and "\n" not in str(info.value)
