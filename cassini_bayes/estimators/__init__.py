"""cassini_bayes.estimators."""
