"""Running a native Job from an operator: in the UI a modal operator polls the Job on a
window-manager timer (the work runs on native threads, so the UI stays responsive), shows a
progress bar and status text, and Esc cancels; headless (``blender -b``) it runs to the end
synchronously, printing progress."""

from __future__ import annotations

import bpy

from ..core import native
from ..core.progress import TerminalProgress

POLL_SECONDS = 0.1

# Labels of the jobs running modal now (the panels and the UI test look at it).
running_labels: list = []


class NativeJobOperator:
    """Mix-in for bpy.types.Operator. Subclasses implement:
    start_job(context) -> Job or None (None: it reported why and nothing runs),
    finish_job(context, result) -> operator return set, or the next Job of a chain (its
    result comes to finish_job in turn), and may override cleanup_job(context) (called once
    at the end, after success, failure and cancel alike)."""

    job_label = "Working"
    _job = None
    _timer = None

    def start_job(self, context):
        raise NotImplementedError

    def finish_job(self, context, result):
        raise NotImplementedError

    def cleanup_job(self, context):
        pass

    def run_job(self, context):
        """Starts the job; modal in the UI, synchronous in the background."""
        job = self.start_job(context)
        if job is None:
            self.cleanup_job(context)
            return {"CANCELLED"}
        self._job = job
        if bpy.app.background or context.window is None:
            while True:
                running = self._job
                outcome = self._conclude(context, lambda: running.run(TerminalProgress()))
                if isinstance(outcome, set):
                    return outcome
        wm = context.window_manager
        self._timer = wm.event_timer_add(POLL_SECONDS, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        running_labels.append(self.job_label)
        self._status(context, f"{self.job_label}: starting (Esc cancels)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
            self._status(context, f"{self.job_label}: cancelling")
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":  # (any timer: events do not say which one fired)
            return {"PASS_THROUGH"}
        if not job.done:
            context.window_manager.progress_update(int(1000 * max(0.0, min(1.0, job.fraction))))
            self._status(context, f"{self.job_label}: {job.stage} {100.0 * job.fraction:.0f}% (Esc cancels)")
            return {"PASS_THROUGH"}
        outcome = self._conclude(context, job.result)
        if isinstance(outcome, set):
            self._end_modal(context)
            return outcome
        return {"PASS_THROUGH"}  # the next job of the chain runs; keep polling

    def cancel(self, context):
        # Blender ends the operator (window closed, file loaded): stop the work too.
        if self._job is not None:
            self._job.cancel()
            self._job.wait(-1)
            self._job = None
            self.cleanup_job(context)
        self._end_modal(context)

    def _end_modal(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
            wm.progress_end()
            running_labels.remove(self.job_label)
        self._status(context, None)

    def _status(self, context, text):
        workspace = getattr(context, "workspace", None)
        if workspace is not None and not bpy.app.background:
            workspace.status_text_set(text)

    def _conclude(self, context, fetch_result):
        """The job's outcome (fetch_result gives its result or raises its error): an operator
        return set, or the next Job of the chain (then the current one)."""
        _native = native.load()
        self._job = None
        outcome = {"CANCELLED"}
        try:
            outcome = self.finish_job(context, fetch_result())
        except _native.Cancelled:
            self.report({"WARNING"}, f"{self.job_label}: cancelled")
        except (_native.InputError, _native.NativeIOError, OSError, ValueError, RuntimeError) as error:
            self.report({"ERROR"}, f"{self.job_label} failed: {error}")
        if isinstance(outcome, set):
            self.cleanup_job(context)
        else:
            self._job = outcome
        return outcome
