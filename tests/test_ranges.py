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


def test_one_rule_stop_below_start_is_refused_everywhere():
    from tippedisk_analysis.ranges import check_axis, check_range

    with pytest.raises(ParameterError, match="STOP < START; give START < STOP"):
        parse_range("80:10:3", "omega")
    with pytest.raises(ParameterError, match="stop < start; give start < stop") as info:
        check_range((80, 10, 3), "omega")
    assert "--" not in str(info.value)  # API wording
    with pytest.raises(ParameterError, match="increase strictly"):
        check_axis([3.0, 2.0, 1.0], "omega")


@pytest.mark.parametrize("value", [(1, 2), "1:2:3", (1, 2, 2.5), (True, 2, 3), None])
def test_python_ranges_name_the_fix_in_python_words(value):
    from tippedisk_analysis.ranges import check_range

    with pytest.raises(ParameterError, match=r"omega=\(10, 80, 64\)"):
        check_range(value, "omega")


def test_python_ranges_accept_numbers_and_integral_n():
    from tippedisk_analysis.ranges import check_range

    assert check_range((10, 80, 64.0), "omega") == (10.0, 80.0, 64)
    assert check_range(0.3, "mu") == (0.3, 0.3, 1)
