"""The experiment kinds, one module each; :func:`~surrogate_rbrdo.runner.kinds.discover`
imports every module here (so adding a kind is adding a file)."""
