"""Evaluation: every controller on every record in the same simulator, and the tables and
plots. Depends on `physics`, `control` and `learning`."""
