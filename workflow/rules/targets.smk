# One registry of the study's outputs.
#
# Every stage registers its rules here, once, right after defining them:
#
#     register(rules.figure, report=("png",), fig=FIGURES)
#
# The final targets (rule all), the report's inputs, the archive's inputs and
# the run times the report lists are all read from this registry, so an
# output path is written once, in its rule.  Adding a figure takes one rule
# (registered) and one caption file, workflow/report/<name>.rst.  A shown
# output carries its caption, category and subcategory in its report() flag,
# and both reports (Snakemake's and the HTML page) read them from there.
import glob
import itertools

from snakemake.iocontainers import Wildcards

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


def _output(rule, name):
    return rule.output[name] if isinstance(name, int) else getattr(rule.output, name)


def report_sections():
    """What the HTML report shows, one entry per file, in registration order.

    Each entry: the file's path, its caption file (rst, relative to the working directory), the
    category and subcategory of its report() flag with the wildcards applied, and the wildcards.
    """
    entries = []
    for rule, shown, wc in REGISTRY:
        for name in shown:
            pattern = _output(rule.rule, name)
            flag = pattern.flags.get("report")
            if flag is None or flag.caption is None or flag.category is None:
                raise WorkflowError(
                    f"output {name!r} of {rule.rule.name} is registered for the report, so it needs "
                    "report(..., caption=, category=, subcategory=)"
                )
            for values in _combinations(wc):
                wildcards = Wildcards(fromdict=values)
                entries.append(
                    {
                        "path": _expand([_output(rule, name)], values)[0],
                        "caption": os.path.relpath(flag.caption.get_path_or_uri(secret_free=True)),
                        "category": _flag_text(flag.category, wildcards),
                        "subcategory": _flag_text(flag.subcategory, wildcards),
                        "wildcards": values,
                    }
                )
    return entries


def report_captions():
    """Every caption file (rst) of the workflow, with those its captions include."""
    return sorted(set(glob.glob(os.path.join(REPORT_DIR, "*.rst"))) - {OVERVIEW})


def _combinations(wildcards):
    names = list(wildcards)
    return [dict(zip(names, values)) for values in itertools.product(*(wildcards[n] for n in names))]


def _flag_text(value, wildcards):
    """A report() flag's category or subcategory as Snakemake shows it: called, then formatted."""
    value = value(wildcards) if callable(value) else value
    return None if value is None else value.format(**wildcards)


def study_benchmarks():
    """The benchmark file of every registered job, for the report's run times."""
    return [f for rule, _, wc in REGISTRY for f in _expand([rule.benchmark], wc)]
