"""The papers' least-squares estimators, kept as baselines for the Bayesian models.

Plain NumPy on top of the pure-JAX physics; each returns a typed result with the estimate, the
residual rms, the rank and condition number of its regression and any warnings, and raises
:class:`~cassini_bayes.errors.UnidentifiableError` (naming the parameters) when the data cannot
identify what was asked.
"""

from cassini_bayes.estimators.accelerometer import (ACC_SCALE_M_S_PER_DN, accelerometer_delta_v,
                                                    z_thrust_from_delta_v)
from cassini_bayes.estimators.baseline import (THRUST_GROUPINGS, fit_inertia_baseline,
                                               fit_rwa4_baseline, fit_thrust_baseline,
                                               wheel_momentum)
from cassini_bayes.estimators.inertia import (InertiaFit, fit_all_axes, fit_axis_by_axis,
                                              fit_free_momentum, single_axis_mask, table1_errors)
from cassini_bayes.estimators.leak import leak_torque, momentum_correction, residual_momentum
from cassini_bayes.estimators.lstsq import LstsqFit, solve_lstsq
from cassini_bayes.estimators.rwa4 import (Rwa4Fit, axis_error_deg, fit_axis_four_wheel,
                                           fit_axis_rcs, fit_axis_rwa, momentum_balance,
                                           window_mask)
from cassini_bayes.estimators.thrust import (ThrustFit, fit_mean, fit_y_mean, fit_y_pairs,
                                             fit_y_thrusters, fit_z_thrusters, ratio_corrected,
                                             regression_inputs)
from cassini_bayes.estimators.torque import CASSINI_T, nongravitational_torque

__all__ = [
    "ACC_SCALE_M_S_PER_DN", "accelerometer_delta_v", "z_thrust_from_delta_v",
    "THRUST_GROUPINGS", "fit_inertia_baseline", "fit_rwa4_baseline", "fit_thrust_baseline",
    "wheel_momentum",
    "InertiaFit", "fit_all_axes", "fit_axis_by_axis", "fit_free_momentum", "single_axis_mask",
    "table1_errors",
    "leak_torque", "momentum_correction", "residual_momentum",
    "LstsqFit", "solve_lstsq",
    "Rwa4Fit", "axis_error_deg", "fit_axis_four_wheel", "fit_axis_rcs", "fit_axis_rwa",
    "momentum_balance", "window_mask",
    "ThrustFit", "fit_mean", "fit_y_mean", "fit_y_pairs", "fit_y_thrusters", "fit_z_thrusters",
    "ratio_corrected", "regression_inputs",
    "CASSINI_T", "nongravitational_torque",
]
