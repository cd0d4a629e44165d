import pytest

import tippedisk_analysis as td


def pytest_addoption(parser):
    parser.addoption("--slow", action="store_true",
                     help="also run the long numerical checks marked slow (CI and `bash run.sh test-all` do)")


def pytest_collection_modifyitems(config, items):
    """The default run leaves out the tests marked ``slow``: they are deselected (counted in the summary)."""
    if config.getoption("--slow"):
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]


@pytest.fixture(scope="session")
def table3_euler():
    """ODE Model 1, Table 3, 5 s (the paper's Fig. 13 run)."""
    return td.simulate("ode-euler", 5.0, dt_output=1e-3)


@pytest.fixture(scope="session")
def table3_quaternion():
    """ODE Model 2, Table 3, 5 s."""
    return td.simulate("ode-quaternion", 5.0, dt_output=1e-3)
