"""Studies: many runs at once — hyperparameter tuning (Optuna), multi-seed sweeps on an engine
(local processes or Dask), and statistics over seeds. Depends on `learning` and `evaluation`."""
