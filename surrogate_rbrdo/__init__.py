"""surrogate_rbrdo: reliability-based robust design optimisation of spindle-bearing systems.

The package is layered (see ``docs/architecture.md``): ``core`` holds the protocols, result
dataclasses, registries and error types that every other sub-package shares.
"""

__version__ = "0.1.0"
