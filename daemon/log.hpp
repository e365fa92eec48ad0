// The daemon's log: spdlog's default logger, set up once by main, used by the daemon and its
// drivers (spdlog::warn(...)). Two faces:
//   - under systemd (stderr is the journal: JOURNAL_STREAM names it), every line starts with
//     its sd-daemon priority ("<4>" a warning) and has no timestamp or colour, which journald
//     adds itself; `journalctl -p warning -u rsd` then filters by level;
//   - otherwise a timestamp and the level ("[12:00:01.250] rsd: warning: ..."), the level in
//     colour on a terminal.
// The status line (one line rewritten in place, on a terminal or an interactive run) shares
// the stream: a log line first ends it, so the two never interleave.
//
// Thread contract: every function may be called from any thread; lines are written whole.
#pragma once

#include <spdlog/spdlog.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace rsd::daemon {

// "trace", "debug", "info", "warning" (or "warn"), "error", "critical", "off"; nullopt otherwise.
std::optional<spdlog::level::level_enum> parse_log_level(std::string_view name);

// Whether stderr is connected to the journal (systemd's JOURNAL_STREAM, checked against stderr's
// device and inode as sd_journal_stream_fd(3) describes).
bool stderr_is_journal();

// Installs the default logger on stderr at `level`.
void init_log(spdlog::level::level_enum level = spdlog::level::info);

// An error that ends the run: logged as an error whatever the level (even "off"), so that a
// run never ends without saying why.
void log_fatal(const std::string& message);

// The status line: shows `text` in place of the previous status (with a carriage return);
// end_status_line() moves past it. Nothing when stderr is the journal.
void show_status_line(const std::string& text);
void end_status_line();
// A replay's status line: "rsd: replay [#######.............]  35%  120 frames  84.2 fps"
// (`progress` from 0 to 1, `frames` played in `seconds`).
void show_replay_progress(double progress, uint64_t frames, double seconds);

}  // namespace rsd::daemon
