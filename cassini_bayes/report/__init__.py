"""cassini_bayes.report."""
