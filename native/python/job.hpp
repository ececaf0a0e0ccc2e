// Long native work run off the Python thread: the worker never touches Python, so it runs with
// the GIL released; Python polls progress, asks for cancellation, and collects the result.
// Blender's modal operators poll a Job from a timer; synchronous calls poll it in a loop.
#pragma once

#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include <pybind11/pybind11.h>

#include "lfprobe/progress.hpp"

namespace lfprobe::python {

namespace py = pybind11;

// lfprobe._native.LfprobeWarning (a UserWarning): what a job's Progress::warn collected, raised
// as Python warnings when its result is taken, so the CLI prints them and scripts can filter.
inline PyObject* lfprobe_warning_type() {
    static PyObject* const type =
        PyErr_NewException("lfprobe._native.LfprobeWarning", PyExc_UserWarning, nullptr);
    return type;
}

class Job {
public:
    // `work` runs on a new thread; `to_python` converts its result under the GIL.
    template <class Result>
    Job(std::function<Result(Progress&)> work, std::function<py::object(Result&&)> to_python) {
        auto result = std::make_shared<std::optional<Result>>();
        take_ = [result, to_python]() { return to_python(std::move(**result)); };
        thread_ = std::thread([this, result, work = std::move(work)] {
            try {
                result->emplace(work(progress_));
            } catch (...) {
                error_ = std::current_exception();
            }
            {
                std::lock_guard lock(mutex_);
                done_ = true;
            }
            finished_.notify_all();
        });
    }
    Job(const Job&) = delete;
    Job& operator=(const Job&) = delete;
    ~Job() {
        progress_.request_cancel();
        if (thread_.joinable()) {
            py::gil_scoped_release release;
            thread_.join();
        }
    }

    // Waits up to `seconds` (forever when negative) with the GIL released; true when done.
    bool wait(double seconds) {
        py::gil_scoped_release release;
        std::unique_lock lock(mutex_);
        if (seconds < 0) {
            finished_.wait(lock, [this] { return done_; });
        } else {
            finished_.wait_for(lock, std::chrono::duration<double>(seconds),
                               [this] { return done_; });
        }
        return done_;
    }
    [[nodiscard]] bool done() {
        std::lock_guard lock(mutex_);
        return done_;
    }
    void cancel() { progress_.request_cancel(); }
    [[nodiscard]] const Progress& progress() const { return progress_; }

    // The result, or the native error re-raised as a Python exception. Waits when not done.
    py::object result() {
        wait(-1.0);
        if (thread_.joinable()) {
            py::gil_scoped_release release;
            thread_.join();
        }
        if (error_) {
            std::rethrow_exception(error_);
        }
        if (taken_) {
            throw std::runtime_error("the job's result was already taken");
        }
        taken_ = true;
        for (const std::string& warning : progress_.warnings()) {
            if (PyErr_WarnEx(lfprobe_warning_type(), warning.c_str(), 1) != 0) {
                throw py::error_already_set(); // warnings turned into errors by a filter
            }
        }
        return take_();
    }

    // Runs the job to its end from Python: polls every 0.1 s, calls `callback(fraction, stage)`
    // (when not None) and stops the work when the callback returns False or raises, or when
    // Ctrl-C arrives; the callback's exception (or KeyboardInterrupt) is then re-raised. A
    // Ctrl-C that comes when the work can no longer stop (it finished: its output is written,
    // renamed into place) is not a cancel: the result is returned, as if it came a moment later.
    py::object run(const py::object& callback) {
        while (!wait(0.1)) {
            if (PyErr_CheckSignals() != 0) {
                cancel();
                wait(-1.0);
                if (finished_anyway()) {
                    PyErr_Clear();
                    break;
                }
                throw py::error_already_set();
            }
            if (!callback.is_none()) {
                py::object answer;
                try {
                    answer = callback(progress_.fraction(), progress_.stage());
                } catch (py::error_already_set& error) {
                    cancel();
                    wait(-1.0);
                    if (error.matches(PyExc_KeyboardInterrupt) && finished_anyway()) {
                        break;
                    }
                    throw;
                } catch (...) {
                    cancel();
                    wait(-1.0);
                    throw;
                }
                if (answer.is(py::bool_(false))) {
                    cancel();
                }
            }
        }
        if (!callback.is_none()) {
            try {
                callback(1.0, std::string("done"));
            } catch (py::error_already_set& error) {
                if (!error.matches(PyExc_KeyboardInterrupt)) {
                    throw;
                }
            }
        }
        return result();
    }

private:
    // After a cancel: true when the work had already ended without error (too late to stop).
    bool finished_anyway() {
        std::lock_guard lock(mutex_);
        return done_ && !error_;
    }

    Progress progress_;
    std::function<py::object()> take_;
    std::thread thread_;
    std::mutex mutex_;
    std::condition_variable finished_;
    bool done_ = false;
    bool taken_ = false;
    std::exception_ptr error_;
};

} // namespace lfprobe::python
