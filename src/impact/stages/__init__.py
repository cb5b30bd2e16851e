"""The study's stages, one module (or package) each, named as the stage's config key, its rules file
(``workflow/rules/<stage>.smk``), its ``results/`` folder and its report section."""
