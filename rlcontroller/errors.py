"""The two kinds of user mistake every command reports in one line (no traceback): a configuration that
cannot be used, and a load file that cannot be read. Kept apart from the modules that raise them so the
command line can catch them without loading those."""


class ConfigError(ValueError):
    """A user mistake in a configuration file; `str()` is the one-line message to print."""


class MotionError(ValueError):
    """A ground-motion (or load) file that cannot be read; `str()` names the file and line."""
