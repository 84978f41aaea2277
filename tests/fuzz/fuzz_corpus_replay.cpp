// fuzz_corpus_replay TARGET DIR...: every file under the DIRs through the fuzz target TARGET, in
// the normal build (no clang, no libFuzzer). A finding aborts (the test fails); the corpora hold
// the seeds and every input a fuzz run found, so CI checks them all.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_target.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: fuzz_corpus_replay TARGET DIR...\n");
    return 2;
  }
  const auto& targets = penumbra::fuzz::targets();
  const auto target = targets.find(argv[1]);
  if (target == targets.end()) {
    std::fprintf(stderr, "fuzz_corpus_replay: unknown target '%s'\n", argv[1]);
    return 2;
  }
  std::vector<std::filesystem::path> files;
  for (int i = 2; i < argc; ++i)
    for (const auto& e : std::filesystem::recursive_directory_iterator(argv[i]))
      if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::fprintf(stderr, "fuzz_corpus_replay: no inputs for '%s'\n", argv[1]);
    return 1;
  }
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    std::fprintf(stderr, "%s\n", f.filename().c_str());
    target->second(bytes);
  }
  std::printf("%s: %zu inputs replayed\n", argv[1], files.size());
  return 0;
}
