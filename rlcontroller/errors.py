"""The kinds of user mistake every command reports in one line (no traceback): a configuration that
cannot be used, a load file or test recording that cannot be read, and a model of the user's (an OpenSees
file) that fails.
Kept apart from the modules that raise them so the command line can catch them without loading those."""


class ConfigError(ValueError):
    """A user mistake in a configuration file; `str()` is the one-line message to print."""


class MotionError(ValueError):
    """A ground-motion (or load) file that cannot be read; `str()` names the file and line."""


class RecordingError(ValueError):
    """A vibration test's recording that cannot be read, or from which the modes asked for cannot be
    identified; `str()` names the file (and line) or says what is missing."""


class ModelError(RuntimeError):
    """A model from outside `rlc` (an OpenSees file) that cannot be built or does not converge; `str()` names
    the file, or the record and the time."""
