#pragma once

// A .sdfmap's bytes as the tests edit them: where its records start, its checksum made right
// again, and the files of older format versions made from a new one (io/sdfmap_file.h gives
// the layout).

#include <cstdint>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace sdf_tracker::test {

/// Where a .sdfmap's place memory header, map frame, colour flag, submap and edge counts and first
/// submap record start, and in a file of one submap and no edge, its first block.
constexpr size_t kSdfmapPlacesHeader = 64;
constexpr size_t kSdfmapMapFrame = kSdfmapPlacesHeader + 48;
constexpr size_t kSdfmapColourFlag = kSdfmapMapFrame + 64;
constexpr size_t kSdfmapSubmapCounts = kSdfmapColourFlag + 8;
constexpr size_t kSdfmapFirstSubmap = kSdfmapSubmapCounts + 16;
constexpr size_t kSdfmapSubmapRecord = 136;
constexpr size_t kSdfmapEdgeRecord = 360;
constexpr size_t kSdfmapFirstBlock = kSdfmapFirstSubmap + kSdfmapSubmapRecord;
/// A keyframe's record: its pose, a code per fern and its submap.
constexpr size_t sdfmapKeyframeBytes(size_t ferns) { return 56 + ferns + 4; }

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// The file's bytes with its FNV-1a checksum made right again, as a careful forger would.
inline std::string withValidChecksum(std::string bytes) {
  uint64_t hash = 0xcbf29ce484222325ull;
  for (size_t i = 0; i + sizeof(uint64_t) < bytes.size(); ++i) {
    hash = (hash ^ static_cast<unsigned char>(bytes[i])) * 0x100000001b3ull;
  }
  bytes.replace(bytes.size() - sizeof(hash), sizeof(hash), reinterpret_cast<const char*>(&hash), sizeof(hash));
  return bytes;
}

/// The file an older build would have written of the same map: `current`, a file of one submap,
/// no edge, no colour below version 4, and `keyframes` keyframes of `ferns` ferns, as format
/// `version` (1 to 4): without the submaps' records and the keyframes' submaps (4), the colour
/// flag (3), the map frame (2), the place memory (1).
inline std::string asOlderSdfmapVersion(const std::string& current, int version, size_t keyframes, size_t ferns) {
  const size_t keyframes_at = current.size() - sizeof(uint64_t) - keyframes * sdfmapKeyframeBytes(ferns);
  std::string older = current.substr(0, kSdfmapSubmapCounts) + current.substr(kSdfmapFirstBlock, keyframes_at - kSdfmapFirstBlock);
  if (version >= 2) {
    for (size_t k = 0; k < keyframes; ++k) {
      older += current.substr(keyframes_at + k * sdfmapKeyframeBytes(ferns), sdfmapKeyframeBytes(ferns) - 4);
    }
  }
  if (version <= 3) {
    if (older[kSdfmapColourFlag] != 0) throw std::invalid_argument("a map with colour has no version 3 file");
    older.erase(kSdfmapColourFlag, 8);
  }
  if (version <= 2) older.erase(kSdfmapMapFrame, kSdfmapColourFlag - kSdfmapMapFrame);
  if (version <= 1) older.erase(kSdfmapPlacesHeader, kSdfmapMapFrame - kSdfmapPlacesHeader);
  older[8] = static_cast<char>(version);
  return withValidChecksum(older + std::string(sizeof(uint64_t), '\0'));
}

}  // namespace sdf_tracker::test
