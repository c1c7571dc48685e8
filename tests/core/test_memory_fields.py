"""Every size field of every options class refuses a size whose arrays would not fit, naming
the field (review items 2 and 10: sizes refused before work, the dominant field named)."""

from __future__ import annotations

import re

import pytest

from surrogate_rbrdo.core.memory import check_memory, memory_needs
from surrogate_rbrdo.study import OptimizationOptions, VerificationOptions
from surrogate_rbrdo.surrogates.design_model import DesignModelOptions
from surrogate_rbrdo.surrogates.refine import RefineOptions
from surrogate_rbrdo.surrogates.structured import (
    GlobalOptions,
    ResonanceOptions,
    SubstructureOptions,
)

HUGE = 10 ** 12
#: (options class, fixed fields, size field, the field the message must name)
SIZES = [
    (GlobalOptions, {}, "n_doe", "n_doe"),
    (GlobalOptions, {"active_learning": True}, "al_n_initial", "al_n_initial"),
    (GlobalOptions, {"active_learning": True}, "al_max_added", "al_max_added"),
    (GlobalOptions, {"active_learning": True}, "al_pool_designs",
     "al_pool_designs × al_pool_theta"),
    (GlobalOptions, {"active_learning": True}, "al_pool_theta",
     "al_pool_designs × al_pool_theta"),
    (ResonanceOptions, {}, "n_doe", "n_doe"),
    (ResonanceOptions, {}, "res_n_band", "res_n_band"),
    (ResonanceOptions, {}, "res_n_band_lim", "res_n_band_lim"),
    (ResonanceOptions, {}, "res_band_pool", "res_band_pool"),
    (SubstructureOptions, {}, "n_doe", "n_doe"),
    (SubstructureOptions, {}, "sub_n_speeds", "sub_n_speeds"),
    (OptimizationOptions, {}, "n_theta", "pop_size × n_theta"),
    (OptimizationOptions, {}, "n_gen", "pop_size × n_gen"),
    (OptimizationOptions, {}, "pop_size", "pop_size × n_gen"),
    (VerificationOptions, {}, "n_theta", "n_theta"),
    (VerificationOptions, {"pf_method": "is"}, "is_samples", "is_samples"),
    (VerificationOptions, {"front_designs": 2}, "front_n_theta", "front_n_theta"),
    (VerificationOptions, {}, "campbell_speeds", "campbell_speeds"),
    (DesignModelOptions, {}, "n_train", "n_train"),
    (DesignModelOptions, {}, "n_validate", "n_validate"),
    (RefineOptions, {"rounds": 1}, "theta", "theta"),
    (RefineOptions, {"rounds": 1}, "designs", "designs"),
]


@pytest.mark.parametrize(("cls", "fixed", "size", "blamed"), SIZES,
                         ids=[f"{c.__name__}.{s}" for c, _, s, _ in SIZES])
def test_every_size_field_is_refused_naming_it(cls, fixed, size, blamed):
    check_memory(memory_needs(cls(**fixed), "t"))                  # the defaults fit
    with pytest.raises(ValueError, match=rf"^t\.{re.escape(blamed)} = [0-9 ×]*{HUGE}[0-9 ×]* "
                                         r"is not allowed: the arrays (it sizes|they size) need"):
        check_memory(memory_needs(cls(**fixed, **{size: HUGE}), "t"))


def test_product_of_fields_names_every_factor():
    """pop_size = n_gen = 1e8 (review item 10 blamed n_theta = 40): the archive term
    pop_size × n_gen dominates and is named with both values."""
    o = OptimizationOptions(pop_size=10 ** 8, n_gen=10 ** 8, n_theta=40, p_targets=(0.1,),
                            strategies=())
    needs = memory_needs(o, "optimization")
    assert set(needs) == {"optimization.pop_size × n_theta", "optimization.pop_size × n_gen"}
    # known answer: 256 B per archived individual of the one run, 64 B per response value
    assert needs["optimization.pop_size × n_gen"][1] == 256.0 * 1e16
    assert needs["optimization.pop_size × n_theta"][1] == 64.0 * 1e8 * 40
    with pytest.raises(ValueError, match=r"^optimization\.pop_size × n_gen = 100000000 × "
                                         r"100000000 is not allowed"):
        check_memory(needs)
