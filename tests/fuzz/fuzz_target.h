#pragma once
// One fuzz target per file: PENUMBRA_FUZZ_TARGET(name) { ... } defines LLVMFuzzerTestOneInput
// for libFuzzer (PENUMBRA_FUZZ=ON, clang) or, in the normal build, registers the function for
// fuzz_corpus_replay, which feeds every file of tests/fuzz/corpus/<name>/ through it so CI checks
// the corpora and the findings kept there without clang.
//
// A target calls the parser the apps call and lets only the project's own refusals through
// (expected_refusal): std::runtime_error and std::invalid_argument with a one-line message. A
// crash, an abort, a sanitizer report, another exception type (nlohmann's json::exception,
// std::out_of_range from .at(), std::bad_alloc, a std::filesystem::filesystem_error leaking library
// text) or a message over several lines is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <unistd.h>

namespace penumbra::fuzz {

using TargetFunction = void (*)(std::string_view input);

inline std::map<std::string, TargetFunction>& targets() {
  static std::map<std::string, TargetFunction> all;
  return all;
}

struct Registered {
  Registered(const char* name, TargetFunction f) { targets()[name] = f; }
};

// A scratch folder of this process for parsers that read files (the apps' readers take paths).
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path base = std::filesystem::exists("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    const std::filesystem::path d = base / ("penumbra-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] { std::error_code ec; std::filesystem::remove_all(scratch(), ec); });
    return d;
  }();
  return dir;
}

inline void write(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

[[noreturn]] inline void finding(const char* what, const std::string& message) {
  std::fprintf(stderr, "penumbra fuzz finding: %s: %s\n", what, message.substr(0, 2000).c_str());
  std::abort();
}

// Runs `parse`; the project's refusals pass, anything else aborts (a finding).
template <class F>
void expect_refusal_or_success(F&& parse) {
  auto check = [](const std::exception& e) {
    const std::string message = e.what();
    if (message.find('\n') != std::string::npos || message.size() > 4000) finding("error message not one short line", message);
  };
  try {
    parse();
  } catch (const std::system_error& e) {
    finding("std::system_error (library text)", e.what());
  } catch (const std::runtime_error& e) {
    check(e);
  } catch (const std::invalid_argument& e) {
    check(e);
  }
}

}  // namespace penumbra::fuzz

#ifdef PENUMBRA_FUZZ_REPLAY
#define PENUMBRA_FUZZ_TARGET(name)                                                         \
  static void name##_one(std::string_view input);                                          \
  static const penumbra::fuzz::Registered name##_registered(#name, name##_one);           \
  static void name##_one(std::string_view input)
#else
#define PENUMBRA_FUZZ_TARGET(name)                                                         \
  static void name##_one(std::string_view input);                                          \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {     \
    name##_one(std::string_view(reinterpret_cast<const char*>(data), size));               \
    return 0;                                                                              \
  }                                                                                        \
  static void name##_one(std::string_view input)
#endif
