"""cassini_bayes.analysis."""
