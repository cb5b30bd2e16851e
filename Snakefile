# The study's workflow lives in workflow/Snakefile (the Snakemake layout); this file lets
# `snakemake` run from the repository root, and `snakemake -s workflow/Snakefile` works the same.


include: "workflow/Snakefile"


# an included file cannot set the default target: name it here, as the workflow's own `all`
rule study:
    default_target: True
    input:
        rules.all.input,
