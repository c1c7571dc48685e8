"""The surrogate registry (kind ``"surrogate"``), filled where each model is defined."""

from surrogate_rbrdo.core.registry import Registry

SURROGATES = Registry("surrogate")
