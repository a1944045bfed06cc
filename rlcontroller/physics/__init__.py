"""The physics: the shear building, its step maps, ground motions and records, and the plant built
once from an experiment. Depends on nothing of the package but `config`."""
