"""Controllers designed on the plant: the uncontrolled building, LQG (with its Kalman filters) and
the optimal references with ground-motion preview. Depends on `physics` only."""
