"""Thruster health over many biasing events (pure NumPy, exact).

Two levels: :mod:`~cassini_bayes.inference.health.summary` reduces each event to a Gaussian
summary of its identifiable log thrusts (the channels, found from the events' firings);
:mod:`~cassini_bayes.inference.health.changepoint` pools the summaries into the exact posterior of
a change-point model (a step in each channel's thrust at one unknown date, or no change),
marginalised over a grid of change intervals and event-to-event scatter levels. docs/health.md
describes both and the campaigns that test them.
"""

from cassini_bayes.inference.health.changepoint import (HealthPosterior, HealthPrior,
                                                        health_posterior)
from cassini_bayes.inference.health.summary import (EventSummary, HealthChannels,
                                                    event_channels, event_summary,
                                                    health_channels)

__all__ = ["EventSummary", "HealthChannels", "HealthPosterior", "HealthPrior", "event_channels",
           "event_summary", "health_channels", "health_posterior"]
