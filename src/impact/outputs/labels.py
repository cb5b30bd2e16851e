"""Words the study writes into its results and reads back when it draws them: one place for each."""

#: the status of a numerics run its time budget stopped (``failed: too slow ...``), which the figures mark
TOO_SLOW = "too slow at this setting"

#: the meanings of the 0/1 flag every run records: whether it stopped at the engine's cap on events
EVENT_CAP_MEANINGS = ("finished", "stopped_at_event_cap")
