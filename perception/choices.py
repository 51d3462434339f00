"""The named choices of perception, each defined once: policies, model kinds, belief shifts, decisions.

Standard library only (nothing at all is imported), so the command line can build its ``--help``
and the station configuration can validate its keys without loading NumPy, SciPy or h5py.
"""

__all__ = ["POLICIES", "MODEL_KINDS", "SHIFT_MODES", "DECISION_RULES"]

#: How the sensor moves between taps: names accepted by `perception.policies.make_policy`.
POLICIES = ("active", "stationary", "random")

#: Kinds of likelihood model (`perception.model.train_model`); the first is the papers' model. A station
#: trains any of them (``[perception] likelihood``; torch needs the extra ``learned``).
MODEL_KINDS = ("histogram", "calibrated-histogram", "gaussian", "torch")

#: Belief shift boundary conventions (`perception.bayes.shift`): replicate the edge class (paper 002) or
#: fill uniformly (paper 000 eq. 8).
SHIFT_MODES = ("edge", "uniform")

#: Stop rules (`perception.bayes.decide`): a 'what' marginal crosses theta (papers 002, 003, 004) or any
#: joint class does (paper 001 eq. 3).
DECISION_RULES = ("marginal", "joint")
