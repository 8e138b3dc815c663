#pragma once
// The payload checksum of model files (version 2) and stage state files: four independent lanes over 32-byte
// blocks, so it runs at memory speed on the hundreds of megabytes a vocabulary or a long route's map takes.
#include <cstddef>
#include <cstdint>

namespace binloop {

uint64_t checksum64(const void* data, size_t n);

}  // namespace binloop
