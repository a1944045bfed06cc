"""Learning: the Gymnasium env, the learners, run folders, validation, training and saved policies.
Depends on `physics` and `control`."""
