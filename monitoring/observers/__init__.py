"""The built-in observer types, one module each (see :mod:`monitoring.observer`)."""
