# One registry of the study's outputs.
#
# Every stage registers its rules here, once, right after defining them:
#
#     register(rules.figure, report=("png",), fig=FIGURES)
#
# The final targets (rule all), the report's inputs, the archive's inputs and
# the run times the report lists are all read from this registry, so an
# output path is written once, in its rule.  Adding a figure takes one rule
# (registered) and one caption file, workflow/report/<name>.rst.

REGISTRY = []


def register(rule, report=(), **wildcards):
    """Keep every output of `rule` (a rules.<name> proxy) for each combination of the wildcards' values.

    report: the outputs the HTML report shows (names, or positions for unnamed outputs), in its order.
    """
    REGISTRY.append((rule, tuple(report), wildcards))


def _expand(patterns, wildcards):
    patterns = [str(p) for p in patterns]
    return expand(patterns, **wildcards) if wildcards else patterns


def study_outputs():
    """Every registered output: the study's products."""
    return [f for rule, _, wc in REGISTRY for f in _expand(rule.output, wc)]


def report_inputs():
    """The registered outputs the report shows, stage by stage in registration order."""
    return [f for rule, shown, wc in REGISTRY for name in shown for f in _expand([_output(rule, name)], wc)]


def _output(rule, name):
    return rule.output[name] if isinstance(name, int) else getattr(rule.output, name)


def study_benchmarks():
    """The benchmark file of every registered job, for the report's run times."""
    return [f for rule, _, wc in REGISTRY for f in _expand([rule.benchmark], wc)]
