// Errors as values: every core function that can fail on user input returns Result<T>.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace burnish {

/// A failure with one clear, user-facing line (no trailing newline).
struct Error {
    std::string message;
};

/// Either a value or an Error. Never throws on user input; value() on an error is a programming bug.
template <class T> class [[nodiscard]] Result {
public:
    Result(T value)
        : m_state(std::move(value)) {}
    Result(Error error)
        : m_state(std::move(error)) {}

    bool ok() const { return std::holds_alternative<T>(m_state); }
    explicit operator bool() const { return ok(); }

    const T& value() const& { return std::get<T>(m_state); }
    T& value() & { return std::get<T>(m_state); }
    T&& value() && { return std::get<T>(std::move(m_state)); }
    const T& operator*() const& { return value(); }
    const T* operator->() const { return &value(); }

    /// The error message; empty when ok().
    const std::string& error() const {
        static const std::string none;
        return ok() ? none : std::get<Error>(m_state).message;
    }

private:
    std::variant<T, Error> m_state;
};

/// Result for operations that produce nothing but may fail.
class [[nodiscard]] Status {
public:
    Status() = default;
    Status(Error error)
        : m_error(std::move(error.message))
        , m_failed(true) {}
    static Status success() { return {}; }

    bool ok() const { return !m_failed; }
    explicit operator bool() const { return ok(); }
    const std::string& error() const { return m_error; }

private:
    std::string m_error;
    bool m_failed = false;
};

} // namespace burnish
