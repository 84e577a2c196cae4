"""cassini_bayes.simulate."""
