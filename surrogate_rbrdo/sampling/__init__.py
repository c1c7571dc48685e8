"""Evaluation of an expensive point-wise function: parallel (joblib / Dask), cached, counted.

>>> import numpy as np
>>> res = evaluate_points(np.sum, np.arange(6.0).reshape(3, 2))
>>> res.y.tolist(), res.n_evaluated
([1.0, 5.0, 9.0], 3)
"""

from surrogate_rbrdo.sampling.evaluate import BACKENDS, SampleResult, evaluate_points

__all__ = ["BACKENDS", "SampleResult", "evaluate_points"]
