"""``python -m cassini_bayes.cli``: the ``cassini-bayes`` command."""

from cassini_bayes.cli import entry

entry()
