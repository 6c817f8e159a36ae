// What every fuzz target shares. The readers take a path, so each input is
// written to a file first: one per process and file name, rewritten for every
// input (a fresh file each time would cost more than most parses).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace docunfold::fuzz {

// Writes `size` bytes to <a temporary folder of this process>/<name> and
// returns its path. The folder goes when the process exits normally.
std::filesystem::path WriteInput(const uint8_t* data, size_t size, const std::string& name);

}  // namespace docunfold::fuzz
