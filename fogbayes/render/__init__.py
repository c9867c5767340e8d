"""HTML calibration reports: the sections, headline and page of ``fogbayes report`` and :func:`fogbayes.report`.

Renders only: the numbers come from :mod:`fogbayes.workflow.report`, figures from :mod:`fogbayes.plot`.
"""
