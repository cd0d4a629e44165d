"""Nonlinear-dynamics analysis: stationary spinning solutions (:mod:`.stationary`), their
eigenvalue stability (:mod:`.stability`) and stability maps with critical spin speeds (:mod:`.maps`)."""
