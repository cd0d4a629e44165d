"""Named layouts of the arrays the numba step loop shares with Python (one place for every index).

numba reads these module-level integers as compile-time constants.
"""

# float parameter vector ``par``
(M, E, RADIUS, A_S, B_S, C_S, GRAVITY, MU, EPS, MU_TAU, MU_R, CONTACT_RADIUS, E_N, E_T, E_TAU, E_R, DT, TOL,
 R_N, R_T, R_TAU, R_R, SIN_FALL_ANGLE, CONTENSOU_TORQUE_SHARE, N_PAR) = range(25)

# integer flags ``flags``
PARAMETERIZATION, LAW, PIVOT_CONTOUR, MAX_ITER, NORMALIZE_QUATERNION, STORE_EVERY, N_FLAGS = range(7)

# impulse kinds of one contact: normal, tangential x and y (I-frame), pivoting, contour
IMPULSE_N, IMPULSE_TX, IMPULSE_TY, IMPULSE_TAU, IMPULSE_R, N_IMPULSES = range(6)
N_CONTACTS = 3  # candidate contact points C1-C3 (2.10)-(2.11)
MAX_COLUMNS = N_CONTACTS * N_IMPULSES  # force directions of one step

# statistics of the current storage interval ``stats``
STAT_ITER_MAX, STAT_ITER_SUM, STAT_STEPS, STAT_FAILURES, STAT_N_CLOSED, N_STATS = range(6)

# columns of a stored row ``out``: time, q (7), u (6), gaps (3), impulses (kind-major, 5 x 3), statistics
COL_TIME = 0
COL_Q = 1
COL_U = COL_Q + 7
COL_GAP = COL_U + 6
COL_IMPULSE = COL_GAP + N_CONTACTS  # + kind * N_CONTACTS + contact
COL_N_CLOSED = COL_IMPULSE + N_IMPULSES * N_CONTACTS
COL_ITER_MAX = COL_N_CLOSED + 1
COL_ITER_MEAN = COL_ITER_MAX + 1
N_COLUMNS = COL_ITER_MEAN + 1

# how a call of the step loop ended
STATUS_OK, STATUS_NONFINITE, STATUS_FELL = 0, 1, 2
STATUS_NAMES = {STATUS_OK: "completed", STATUS_NONFINITE: "nonfinite", STATUS_FELL: "fell"}
