"""The HTML report of a scenario or store (:mod:`raysim.report.html`) and the one way
to draw a map (:mod:`raysim.report.figures`)."""
