"""Learning: the Gymnasium env and its batched counterpart, the learners and their vector env, run
folders, validation, training and saved policies. Depends on `physics` and `control`."""

from rlcontroller import register_env

register_env()
