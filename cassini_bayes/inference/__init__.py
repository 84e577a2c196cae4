"""cassini_bayes.inference."""
