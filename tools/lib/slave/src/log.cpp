// The slave's console log (see slave/log.hpp).
#include "slave/log.hpp"

#include <unistd.h>

#include <ostream>

namespace slave {

std::optional<LogLevel> parse_log_level(std::string_view t) {
    if (t == "error") return LogLevel::Error;
    if (t == "warn" || t == "warning") return LogLevel::Warn;
    if (t == "info") return LogLevel::Info;
    if (t == "debug") return LogLevel::Debug;
    return std::nullopt;
}

std::string_view log_level_name(LogLevel level) {
    switch (level) {
        case LogLevel::Error:
            return "error";
        case LogLevel::Warn:
            return "warning";
        case LogLevel::Info:
            return "info";
        case LogLevel::Debug:
            return "debug";
    }
    return "info";
}

void Log::write(LogLevel level, std::string_view text) {
    if (!enabled(level)) return;
    out_ << program_ << ": ";
    if (level != LogLevel::Info) {
        const char* on = level == LogLevel::Error ? "\033[31m" : level == LogLevel::Warn ? "\033[33m" : "";
        if (colour_ && *on != 0) out_ << on;
        out_ << log_level_name(level) << ':';
        if (colour_ && *on != 0) out_ << "\033[0m";
        out_ << ' ';
    }
    out_ << text << '\n';
    out_.flush();
}

bool stderr_is_terminal() {
    return ::isatty(STDERR_FILENO) == 1;
}

}  // namespace slave
