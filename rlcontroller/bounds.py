"""Sane bounds: beyond them a value is a typo or a unit mistake, not a building. The configuration checks
every input against them (and names the bound in its message); the command line checks its options
against the same numbers without loading the configuration."""

MAX_FLOORS = 100
MAX_MASS = 1.0e9  # kg per floor
MAX_STIFFNESS = 1.0e12  # N/m per story
MAX_FORCE = 1.0e9  # N
MAX_GROUND_ACCELERATION = 100.0  # m/s^2, about 10 g
MIN_TIME_STEP, MAX_TIME_STEP = 1.0e-4, 1.0  # s
MAX_DURATION = 3600.0  # s, one motion
MAX_HISTORY = 500  # control steps in the observation
MAX_SEED = 2**32 - 1
MAX_TOTAL_STEPS = 10**9
MAX_ENVS = 256
MAX_HORIZON = 200  # control steps of an MPC horizon
