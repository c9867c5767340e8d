"""HTML calibration reports: the sections, the headline and the page that
``fogbayes report`` and :func:`fogbayes.report` write.

This package renders only: what a report shows is computed by
:mod:`fogbayes.workflow.report` (fit, compensate, Allan analysis, intervals), which hands
the numbers to the sections here. Figures come from :mod:`fogbayes.plot`; nothing here
fits a model.
"""
