// What every occtrack fuzz target shares: the line between an expected outcome (a documented exception with
// a message) and a finding (anything else), and the checks a harness makes on what it parsed.
//
// A finding aborts, so that libFuzzer records the input as a crash (crash-<sha1> in the working directory or
// under -artifact_prefix); crashes, sanitizer reports, leaks, timeouts and the malloc limit are findings of
// libFuzzer itself.
#pragma once

#include <cxxabi.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "occtrack/io/error.hpp"

namespace occtrack::fuzz {

/// Which exceptions count as a clean refusal of the input.
enum class Accept {
  /// Only io::InputError whose message starts with "SOURCE: " (the io parsers document exactly that).
  input_error,
  /// io::InputError, std::invalid_argument, or another std::runtime_error, each with a non-empty message
  /// (the model and dataset loaders, whose contracts are looser).
  documented,
};

[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "\n==occtrack-fuzz== FINDING: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

inline void check(bool condition, const std::string& what) {
  if (!condition) finding(what);
}

inline std::string type_name(const std::type_info& type) {
  int status = 0;
  std::unique_ptr<char, void (*)(void*)> name(abi::__cxa_demangle(type.name(), nullptr, nullptr, &status), std::free);
  return status == 0 && name ? name.get() : type.name();
}

/// Runs `body`; returns normally when it succeeds or throws an accepted exception, aborts otherwise.
/// `source` is the name the harness gave the input (the expected start of every io::InputError message).
template <typename Body>
void run(Accept accept, const std::string& source, Body&& body) {
  try {
    body();
  } catch (const io::InputError& e) {
    const std::string message = e.what();
    if (accept == Accept::input_error)
      check(message.rfind(source + ": ", 0) == 0 && message.size() > source.size() + 2,
            "io::InputError does not start with \"" + source + ": \" and a rule: \"" + message + "\"");
    else
      check(!message.empty(), "io::InputError without a message");
  } catch (const std::invalid_argument& e) {
    if (accept == Accept::input_error) finding("std::invalid_argument escaped: " + std::string(e.what()));
    check(*e.what() != '\0', "std::invalid_argument without a message");
  } catch (const std::runtime_error& e) {
    if (accept == Accept::input_error) finding(type_name(typeid(e)) + " escaped: " + e.what());
    check(*e.what() != '\0', type_name(typeid(e)) + " without a message");
  } catch (const std::exception& e) {
    // std::bad_alloc, std::length_error, std::out_of_range, nlohmann::json::exception, ...
    finding(type_name(typeid(e)) + " escaped: " + e.what());
  } catch (...) {
    finding("an exception that is not a std::exception escaped");
  }
}

}  // namespace occtrack::fuzz
