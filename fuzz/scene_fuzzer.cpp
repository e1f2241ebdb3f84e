// libFuzzer target for the JSON scene loader (docs/fuzzing.md). Any input is fed to
// load_world_from_string; a rejection must be a std::exception (JsonError or another
// std::exception with a message). Nothing else is caught: an abort, a sanitizer report,
// a hang or a leak is a bug the fuzzer reports.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "lib/scene/scene_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // Relative "obj" paths resolve against a folder that does not exist, so the fuzzer cannot
    // wander the file system through mesh files.
    auto world = tb::load_world_from_string(text, "<fuzz>", "/nonexistent-fuzz-dir");
    (void)world;
    static const bool verbose_ok = std::getenv("TB_FUZZ_VERBOSE") != nullptr;
    if (verbose_ok) std::fprintf(stderr, "accepted\n");
  } catch (const std::exception& e) {
    // An expected rejection; it must say why. TB_FUZZ_VERBOSE=1 prints it (to triage inputs).
    static const bool verbose = std::getenv("TB_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "rejected: %s\n", e.what());
    if (e.what() == nullptr || e.what()[0] == '\0') __builtin_trap();
    return 0;
  }
  return 0;
}
