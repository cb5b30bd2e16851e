"""Words the study writes into its results and reads back when it draws them: one place for each."""

#: the status of a numerics run its time budget stopped (``failed: too slow ...``), which the figures mark
TOO_SLOW = "too slow at this setting"
