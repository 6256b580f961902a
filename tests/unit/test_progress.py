"""The run's progress display: warnings from the engine worker reach the user
whether or not a progress bar is shown."""

import io

from vibrofeed.run_progress import RunProgress


def test_warnings_are_printed_without_a_bar():
    stream = io.StringIO()
    progress = RunProgress("bulk_feeder", enabled=False, stream=stream)
    progress({"event": "run", "n_steps": 10, "dt": 1e-6})
    progress({"event": "warning", "message": "2 part(s) disappeared without crossing the outlet"})
    progress.close()
    assert stream.getvalue() == ("vibrofeed: warning: bulk_feeder: 2 part(s) disappeared without "
                                 "crossing the outlet\n")


def test_warnings_are_printed_beside_a_bar():
    stream = io.StringIO()
    progress = RunProgress("bulk_feeder", enabled=True, stream=stream)
    progress({"event": "run", "n_steps": 10, "dt": 1e-6})
    progress({"event": "warning", "message": "no body template"})
    progress({"event": "progress", "step": 5, "time": 5e-6})
    progress({"event": "done"})
    assert "vibrofeed: warning: bulk_feeder: no body template" in stream.getvalue()
