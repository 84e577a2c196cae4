"""The entry points, one per command, called right after the inputs are read.
"""

from __future__ import annotations

from collections.abc import Sequence

from cassini_bayes.consistency._attitude import AttitudeAgreement, check_attitude_rates
from cassini_bayes.consistency._gyro_bias import check_gyro_bias
from cassini_bayes.consistency._identifiability import check_inertia_excitation, check_rwa4_method
from cassini_bayes.consistency._momentum import MomentumScale, check_wheel_units
from cassini_bayes.consistency._pulses import _derived_on_times, check_pulses_match_on_times
from cassini_bayes.consistency._quantisation import check_rate_quantisation
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import (
    PulseLog,
    Telemetry,
)


def check_telemetry_data(tel: Telemetry, spacecraft: Spacecraft | None = None,
                         pulses: PulseLog | None = None
                         ) -> tuple[AttitudeAgreement | None, MomentumScale | None]:
    """Every physics check one telemetry file (and its pulse log) allows: attitude vs rates,
    quantised rates (a warning), pulse log vs ``on_*`` columns, and with a spacecraft model the
    wheel units and the gyro bias (a warning).

    Returns the attitude agreement and the momentum fit (``None`` where not identifiable or,
    for the momentum, without a spacecraft model), for a summary.
    """
    attitude = check_attitude_rates(tel)
    check_rate_quantisation(tel)
    on = tel.on_times
    if pulses is not None:
        check_pulses_match_on_times(tel, pulses)
        if on is None:
            on = _derived_on_times(tel, pulses)
    momentum = check_wheel_units(tel, spacecraft, on) if spacecraft is not None else None
    if spacecraft is not None:
        check_gyro_bias(tel, spacecraft)
    return attitude, momentum


def check_inertia_data(tels: Sequence[Telemetry], spacecraft: Spacecraft) -> None:
    """Checks before ``fit inertia``: each file's attitude, rates and wheel units; then that the
    slews excite more than one axis."""
    for tel in tels:
        check_telemetry_data(tel, spacecraft)
    check_inertia_excitation(tels)


def check_thrust_data(events: Sequence[tuple[Telemetry, PulseLog]],
                      spacecraft: Spacecraft) -> None:
    """Checks before ``fit thrust``: per event, attitude and rates, pulse log vs ``on_*``
    columns, and wheel units (stretches between the logged firings)."""
    for tel, log in events:
        check_telemetry_data(tel, spacecraft, log)


def check_rwa4_data(tel: Telemetry, spacecraft: Spacecraft, method: str,
                    wheel: str = "RWA4") -> None:
    """Checks before ``fit wheel-axis`` (``fit rwa4``: ``wheel`` RWA4): attitude, rates and
    wheel units, and that ``method`` suits how the data were controlled."""
    check_telemetry_data(tel, spacecraft)
    check_rwa4_method(tel, method, wheel)
