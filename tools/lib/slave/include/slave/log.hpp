#pragma once
// The slave's console log: one line per event on a stream (stderr), "ecat-slave: [level: ]text", with no
// time stamp (the journal or the terminal adds one) and colour only on a terminal. --quiet shows errors only,
// --log-level chooses error, warn, info (the default) or debug.
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string_view>

namespace slave {

enum class LogLevel : uint8_t { Error = 0, Warn = 1, Info = 2, Debug = 3 };

// "error", "warn" (or "warning"), "info", "debug"; nullopt for anything else.
std::optional<LogLevel> parse_log_level(std::string_view text);
std::string_view log_level_name(LogLevel level);

class Log {
  public:
    // colour: mark warnings and errors with ANSI colour (for a terminal; never for a pipe or the journal).
    explicit Log(std::ostream& out, LogLevel level = LogLevel::Info, bool colour = false,
                 std::string_view program = "ecat-slave")
        : out_(out), level_(level), colour_(colour), program_(program) {}

    void set_level(LogLevel level) { level_ = level; }
    LogLevel level() const { return level_; }
    bool enabled(LogLevel level) const { return level <= level_; }
    std::ostream& stream() const { return out_; }
    bool colour() const { return colour_; }

    // Writes one line (and flushes it) if the level is enabled.
    void write(LogLevel level, std::string_view text);
    void error(std::string_view text) { write(LogLevel::Error, text); }
    void warn(std::string_view text) { write(LogLevel::Warn, text); }
    void info(std::string_view text) { write(LogLevel::Info, text); }
    void debug(std::string_view text) { write(LogLevel::Debug, text); }

  private:
    std::ostream& out_;
    LogLevel level_;
    bool colour_;
    std::string_view program_;
};

// Whether stderr is a terminal (colour) and not redirected, e.g. to the journal.
bool stderr_is_terminal();

}  // namespace slave
