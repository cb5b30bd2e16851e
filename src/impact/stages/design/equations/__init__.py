"""Design equations: the formulas (:mod:`.formulas`) and the study's fit of them, shipped as fit.json.

A package of its own so that the shipped fit is a data file of this package alone: the code digest that
decides which jobs rerun (impact.outputs.code_deps) counts a package's data files for whoever imports it.
"""
