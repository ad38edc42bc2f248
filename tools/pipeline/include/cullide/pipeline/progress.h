// A progress bar on stderr for the commands that can run long (study, prune, oracle, trace
// record and replay, validate): one line, redrawn in place.
//
// Conventions
//   - stderr only, never stdout (stdout may carry JSON or be piped). Shown when the mode is
//     Always, or Auto and stderr is a terminal; otherwise nothing is written and nothing is timed:
//     a hidden bar is a few branches per update, and never changes a result or a file.
//   - Redrawn at most every 100 ms (kRedrawSeconds), and always at the first update and when the
//     last step is done; finish() (or the destructor) draws the final state and ends the line.
//     While an exception unwinds, the destructor erases the line instead, so that the error
//     message starts a clean line.
//   - Output to stdout while the bar is drawn goes inside a pause() (the bar is erased first and
//     drawn again after) when stdout and stderr are both terminals; otherwise the two never meet.
//   - Erasing pads with spaces (no escape codes): a forced bar written into a file stays text.
//   - One thread: update the bar from the thread that owns it.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <string_view>

namespace cullide {

enum class ProgressMode { Auto, Always, Never };

// "auto" | "always" | "never"; anything else is InputError("option --progress", ...).
ProgressMode parseProgressMode(const std::string& text);
const char* toString(ProgressMode mode);
// Whether a bar in `mode` is drawn: Always, or Auto with stderr a terminal (isatty).
bool progressShown(ProgressMode mode);

class Progress {
public:
    static constexpr double kRedrawSeconds = 0.1;

    // `label` starts the line ("prune"); `total` steps, each one `unit` ("frames").
    Progress(std::string label, size_t total, std::string unit, ProgressMode mode);
    Progress(std::string label, size_t total, std::string unit, bool shown);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    bool shown() const { return shown_; }
    // Whether an update now would redraw: callers with a costly detail text build it only then.
    bool due() const;
    // `done` of the total steps are complete; `detail` says what is under way (e.g. "frame 3,
    // level 2"). Redraws when due, or when `done` reaches the total.
    void update(size_t done, std::string_view detail = {});
    // Draws the final state and ends the line; later updates are ignored. Idempotent.
    void finish();

    // Erases the bar while stdout is written to (when both are terminals) and redraws it when
    // the pause ends, stdout flushed first: `{ auto p = bar.pause(); std::printf(...); }`.
    class Pause {
    public:
        explicit Pause(Progress* p);
        ~Pause();
        Pause(const Pause&) = delete;
        Pause& operator=(const Pause&) = delete;

    private:
        Progress* progress_;
    };
    Pause pause() { return Pause(this); }

private:
    void draw();
    void erase();
    void write(const std::string& text);

    std::string label_, unit_, detail_;
    size_t total_ = 0, done_ = 0;
    bool shown_ = false, finished_ = false, drawn_ = false;
    bool stale_ = false;  // updated since last drawn
    bool interleaved_ = false;  // stdout and stderr both terminals: stdout output erases the bar
    size_t width_ = 0;  // characters of the line last drawn
    int exceptions_ = 0;  // std::uncaught_exceptions() at construction
    std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace cullide
