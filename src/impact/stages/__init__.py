"""The study's stages, one module (or package) each, named as the stage's config key and its rules file
(``workflow/rules/<stage>.smk``); ``docs/architecture.md`` lists where each writes."""
