import pytest

import tippedisk_analysis as td


@pytest.fixture(scope="session")
def table3_euler():
    """ODE Model 1, Table 3, 5 s (the paper's Fig. 13 run)."""
    return td.simulate("ode-euler", 5.0, dt_output=1e-3)


@pytest.fixture(scope="session")
def table3_quaternion():
    """ODE Model 2, Table 3, 5 s."""
    return td.simulate("ode-quaternion", 5.0, dt_output=1e-3)
