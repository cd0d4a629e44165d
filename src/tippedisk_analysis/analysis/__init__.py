"""Analysis of whole trajectories: Poincaré sections, outcome maps, bifurcation diagrams."""
