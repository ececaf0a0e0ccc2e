"""Running a native Job from an operator: in the UI a modal operator polls the Job on a
window-manager timer (the work runs on native threads, so the UI stays responsive), shows a
progress bar and status text, and Esc cancels; headless (``blender -b``) it runs to the end
synchronously, printing progress. ThreadJob gives Python work that chains native calls the
same interface, on a thread of its own."""

from __future__ import annotations

import threading
import warnings

import bpy

from ...core import native
from ...core.progress import TerminalProgress

POLL_SECONDS = 0.1

# Labels of the jobs running modal now (the panels and the UI test look at it).
running_labels: list = []
# The modal operators running now, so that disabling the add-on can stop their jobs.
_running: list = []


def release_running_jobs() -> None:
    """Stops every job still running modal and ends its operator: the add-on is being disabled.
    Blender drops the modal handlers of the operator classes it unregisters, so a job left
    running would never be concluded: its label would keep Bake's poll False and the status
    bar showing it until Blender restarts, and its staging folder would stay."""
    context = bpy.context
    for operator in list(_running):
        try:
            operator.cancel(context)
        except ReferenceError:  # Blender already freed the operator
            pass
    _running.clear()
    running_labels.clear()


class NativeJobOperator:
    """Mix-in for bpy.types.Operator. Subclasses implement:
    start_job(context) -> Job or None (None: it reported why and nothing runs),
    finish_job(context, result) -> operator return set, or the next Job of a chain (its
    result comes to finish_job in turn), and may override cleanup_job(context) (called once
    at the end, after success, failure and cancel alike)."""

    job_label = "Working"
    _job = None
    _timer = None

    def cleanup_job(self, context):
        pass

    def run_job(self, context):
        """Starts the job; modal in the UI, synchronous in the background."""
        for hook in ("start_job", "finish_job"):
            # The mix-in's contract: an operator class that forgot a hook is a programming
            # error, said plainly instead of an AttributeError from deep in the modal loop.
            if not callable(getattr(self, hook, None)):
                raise TypeError(f"{type(self).__name__} uses NativeJobOperator without {hook}()")
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
        _running.append(self)
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
            if self.job_label in running_labels:
                running_labels.remove(self.job_label)
        if self in _running:
            _running.remove(self)
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
            # What the work warned of (a parse cache that could not be written) goes to the
            # status bar and the Info log, as Blender shows an operator's warnings.
            with warnings.catch_warnings(record=True) as heard:
                warnings.simplefilter("always", _native.LfprobeWarning)
                result = fetch_result()
            for warning in heard:
                self.report({"WARNING"}, f"{self.job_label}: {warning.message}")
            outcome = self.finish_job(context, result)
        except _native.Cancelled:
            self.report({"WARNING"}, f"{self.job_label}: cancelled")
        except (_native.InputError, _native.NativeIOError, OSError, ValueError, RuntimeError) as error:
            self.report({"ERROR"}, f"{self.job_label} failed: {error}")
        if isinstance(outcome, set):
            self.cleanup_job(context)
        else:
            self._job = outcome
        return outcome


class ThreadJob:
    """A Job with the native Job's interface (fraction, stage, done, cancel, wait, result, run)
    whose work is a Python function on a thread of its own: for work that chains native calls
    from Python, such as adaptive placement (bake, trace every view, bake again). The function
    is called as work(report) and must not touch bpy; report(fraction, stage) returns False once
    cancel() was asked, and the work then stops with the native Cancelled (native calls given
    report as their progress callback do that themselves)."""

    def __init__(self, work, name: str = "lfprobe job"):
        self.fraction = 0.0
        self.stage = "starting"
        self._cancelled = threading.Event()
        self._finished = threading.Event()
        self._value = None
        self._error = None
        self._taken = False
        self._thread = threading.Thread(target=self._main, args=(work,), name=name, daemon=True)
        self._thread.start()

    def _report(self, fraction: float, stage: str) -> bool:
        self.fraction = float(fraction)
        self.stage = str(stage)
        return not self._cancelled.is_set()

    def _main(self, work):
        try:
            self._value = work(self._report)
        except BaseException as error:  # handed to result(), on the caller's thread
            self._error = error
        finally:
            self._finished.set()

    @property
    def done(self) -> bool:
        return self._finished.is_set()

    def cancel(self) -> None:
        self._cancelled.set()

    def wait(self, seconds: float = -1.0) -> bool:
        return self._finished.wait(None if seconds < 0 else seconds)

    def result(self):
        """The work's return value, or its exception raised again. Waits when not done."""
        self.wait()
        self._thread.join()
        if self._error is not None:
            error, self._error = self._error, None
            raise error
        if self._taken:
            raise RuntimeError("the job's result was already taken")
        self._taken = True
        return self._value

    def run(self, callback=None):
        """Runs to the end from the calling thread as the native Job.run does: calls
        callback(fraction, stage) at once and then every 0.1 s, cancels when it returns False or
        raises (Ctrl-C too)."""
        try:
            while True:
                if callback is not None and callback(self.fraction, self.stage) is False:
                    self.cancel()
                if self.wait(POLL_SECONDS):
                    break
        except BaseException:
            self.cancel()
            self.wait()
            raise
        if callback is not None:
            callback(1.0, "done")
        return self.result()
