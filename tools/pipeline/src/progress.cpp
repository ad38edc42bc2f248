// The progress bar of the long commands (progress.h).
#include "cullide/pipeline/progress.h"

#include "cullide/error.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <exception>

namespace cullide {
namespace {

using Clock = std::chrono::steady_clock;

std::string duration(double s) {
    char buf[32];
    if (s < 10) std::snprintf(buf, sizeof buf, "%.1fs", s);
    else if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
    else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", int(s / 60), int(s) % 60);
    else std::snprintf(buf, sizeof buf, "%dh%02dm", int(s / 3600), int(s / 60) % 60);
    return buf;
}

// Columns of the terminal on stderr (0 when unknown): a line as wide as the terminal would
// wrap, and the carriage return would then redraw only its last row.
size_t terminalColumns() {
    winsize w{};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 0) return w.ws_col;
    return 0;
}

}  // namespace

ProgressMode parseProgressMode(const std::string& text) {
    if (text == "auto") return ProgressMode::Auto;
    if (text == "always") return ProgressMode::Always;
    if (text == "never") return ProgressMode::Never;
    std::string why = "'";
    why += text;
    why += "': auto (when stderr is a terminal), always or never";
    throw InputError("option --progress", why);
}

const char* toString(ProgressMode mode) {
    switch (mode) {
        case ProgressMode::Auto: return "auto";
        case ProgressMode::Always: return "always";
        case ProgressMode::Never: return "never";
    }
    return "auto";
}

bool progressShown(ProgressMode mode) {
    return mode == ProgressMode::Always || (mode == ProgressMode::Auto && ::isatty(STDERR_FILENO));
}

Progress::Progress(std::string label, size_t total, std::string unit, ProgressMode mode)
    : Progress(std::move(label), total, std::move(unit), progressShown(mode)) {}

Progress::Progress(std::string label, size_t total, std::string unit, bool shown)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), shown_(shown) {
    if (!shown_) return;
    interleaved_ = ::isatty(STDOUT_FILENO) && ::isatty(STDERR_FILENO);
    start_ = last_ = Clock::now();
    exceptions_ = std::uncaught_exceptions();
}

Progress::~Progress() {
    if (!shown_ || finished_) return;
    if (std::uncaught_exceptions() > exceptions_) {
        erase();  // the error message that follows starts a clean line
        finished_ = true;
        return;
    }
    finish();
}

bool Progress::due() const {
    if (!shown_ || finished_) return false;
    return !drawn_ || std::chrono::duration<double>(Clock::now() - last_).count() >= kRedrawSeconds;
}

void Progress::update(size_t done, std::string_view detail) {
    if (!shown_ || finished_) return;
    const bool last = done >= total_ && done != done_;
    done_ = done;
    detail_.assign(detail);
    stale_ = true;
    if (!last && !due()) return;
    draw();
}

void Progress::finish() {
    if (!shown_ || finished_) return;
    if (!detail_.empty()) detail_.clear(), stale_ = true;
    if (stale_ || !drawn_) draw();  // the final state, once
    write("\n");
    drawn_ = false;
    finished_ = true;
}

void Progress::draw() {
    last_ = Clock::now();
    const double elapsed = std::chrono::duration<double>(last_ - start_).count();
    const double fraction = total_ ? std::min(1.0, double(done_) / double(total_)) : 1.0;
    // 30 characters of bar, fewer on a narrow terminal so that the counts and times still fit.
    const size_t columns = terminalColumns();
    const int barWidth = columns ? std::clamp(int(columns) - 50, 10, 30) : 30;
    const int filled = int(barWidth * fraction);
    // Built stepwise: GCC 12 warns (-Wrestrict) on chains of string + literal.
    std::string line = label_;
    line += " [";
    line.append(size_t(filled), '#');
    line.append(size_t(barWidth - filled), '.');
    line += "] ";
    line += std::to_string(done_);
    line += '/';
    line += std::to_string(total_);
    if (!unit_.empty()) {
        line += ' ';
        line += unit_;
    }
    line += ", ";
    line += duration(elapsed);
    line += " elapsed";
    if (done_ > 0 && done_ < total_) {
        line += ", ETA ";
        line += duration(elapsed / double(done_) * double(total_ - done_));
    }
    if (!detail_.empty()) {
        line += "; ";
        line += detail_;
    }
    if (columns > 1 && line.size() > columns - 1) line.resize(columns - 1);
    std::string text = "\r";
    text += line;
    if (width_ > line.size()) text.append(width_ - line.size(), ' ');  // what is left of a longer line
    width_ = line.size();
    drawn_ = true;
    stale_ = false;
    write(text);
}

void Progress::erase() {
    if (!drawn_) return;
    std::string text = "\r";
    text.append(width_, ' ');
    text += '\r';
    write(text);
    drawn_ = false;
    width_ = 0;
}

void Progress::write(const std::string& text) {
    std::fwrite(text.data(), 1, text.size(), stderr);
    std::fflush(stderr);
}

Progress::Pause::Pause(Progress* p) : progress_(p) {
    if (!p->shown_ || p->finished_ || !p->interleaved_ || !p->drawn_) {
        progress_ = nullptr;
        return;
    }
    std::fflush(stdout);  // what was printed before the bar stays before it
    p->erase();
}

Progress::Pause::~Pause() {
    if (!progress_ || progress_->finished_) return;
    std::fflush(stdout);
    progress_->draw();
}

}  // namespace cullide
