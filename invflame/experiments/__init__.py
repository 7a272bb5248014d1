"""Experiments: configurations, one reconstruction (:mod:`.runner`), the study's comparison
(:mod:`.reproduce`), metrics and figures."""
