"""The grip model: a lifting force a robot can trust.

* :mod:`~deformctl.grip.groups`: the model's inputs (W, D, λ, μ) and the dimensionless groups
  (ω_n, ζ) its network learns from;
* :mod:`~deformctl.grip.model`: :class:`~deformctl.grip.model.GripForceRegressor`, the
  scikit-learn estimator ``L_f = F_w · r(ω_n, ζ)``;
* :mod:`~deformctl.grip.conformal`: the split-conformal upper bound with a relative score;
* :mod:`~deformctl.grip.export`: a fitted model as plain numbers;
* :mod:`~deformctl.grip.fast`: :class:`~deformctl.grip.fast.Predictor`, the numpy-only
  predictor (microseconds per object) that ``predict`` and robots use.

Nothing is imported here, so that ``deformctl.grip.fast`` stays free of scikit-learn and pandas.
Why the model has this form, with the measurements: docs/explanation/model.md.
"""
