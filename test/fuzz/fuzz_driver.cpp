// A seeded random-mutation driver for the fuzz targets, for compilers without libFuzzer (gcc):
//   fuzz_<target> CORPUS_DIR SECONDS [SEED]
// Runs every corpus file once, then mutates corpus files (bit flips, byte changes, insertions,
// deletions, duplicated runs, truncation, splices, boundary numbers in text) until SECONDS have
// passed. Built with ASan and UBSan, a crash or a sanitizer report ends the process with a
// non-zero exit; the input being read is then in the target's /tmp/sdf_tracker_fuzz_* file.
// With clang, link the targets with -fsanitize=fuzzer instead and this file is not needed.

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

using Bytes = std::vector<uint8_t>;

/// At most this large an input (the readers' own caps are tested with small files claiming more).
constexpr size_t kMaxInputBytes = 1 << 20;

Bytes mutate(Bytes input, const std::vector<Bytes>& corpus, std::mt19937_64& rng) {
  auto pick = [&rng](size_t n) { return n == 0 ? 0 : static_cast<size_t>(rng() % n); };
  static const char* kTokens[] = {"0", "-1", "2147483647", "-2147483648", "4294967296", "1e308", "nan", "inf",
                                  "99999999999999999999", " ", "\n", "#", "\"", ">", "<", "_"};
  const int mutations = 1 + static_cast<int>(rng() % 8);
  for (int m = 0; m < mutations; ++m) {
    switch (rng() % 8) {
      case 0:  // flip a bit
        if (!input.empty()) input[pick(input.size())] ^= static_cast<uint8_t>(1u << (rng() % 8));
        break;
      case 1:  // a random byte
        if (!input.empty()) input[pick(input.size())] = static_cast<uint8_t>(rng());
        break;
      case 2: {  // insert random bytes
        const size_t at = pick(input.size() + 1), n = 1 + pick(16);
        Bytes bytes(n);
        for (auto& b : bytes) b = static_cast<uint8_t>(rng());
        input.insert(input.begin() + at, bytes.begin(), bytes.end());
        break;
      }
      case 3: {  // delete a run
        if (input.empty()) break;
        const size_t at = pick(input.size()), n = 1 + pick(std::min<size_t>(64, input.size() - at));
        input.erase(input.begin() + at, input.begin() + std::min(input.size(), at + n));
        break;
      }
      case 4: {  // duplicate a run
        if (input.empty()) break;
        const size_t at = pick(input.size()), n = 1 + pick(std::min<size_t>(256, input.size() - at));
        const Bytes run(input.begin() + at, input.begin() + std::min(input.size(), at + n));
        input.insert(input.begin() + pick(input.size() + 1), run.begin(), run.end());
        break;
      }
      case 5:  // truncate
        if (!input.empty()) input.resize(pick(input.size()));
        break;
      case 6: {  // splice with another corpus entry
        const Bytes& other = corpus[pick(corpus.size())];
        if (other.empty() || input.empty()) break;
        const size_t at = pick(input.size()), from = pick(other.size());
        input.resize(at);
        input.insert(input.end(), other.begin() + from, other.end());
        break;
      }
      default: {  // a boundary number or a delimiter where text may be
        const std::string token = kTokens[pick(std::size(kTokens))];
        input.insert(input.begin() + pick(input.size() + 1), token.begin(), token.end());
        break;
      }
    }
  }
  if (input.size() > kMaxInputBytes) input.resize(kMaxInputBytes);
  return input;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR SECONDS [SEED]\n", argv[0]);
    return 2;
  }
  std::vector<Bytes> corpus;
  for (const auto& entry : std::filesystem::directory_iterator(argv[1])) {
    std::ifstream in(entry.path(), std::ios::binary);
    corpus.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  if (corpus.empty()) {
    std::fprintf(stderr, "%s: the corpus %s is empty\n", argv[0], argv[1]);
    return 2;
  }
  const double seconds = std::atof(argv[2]);
  std::mt19937_64 rng(argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1);
  size_t runs = 0;
  for (const Bytes& input : corpus) LLVMFuzzerTestOneInput(input.data(), input.size()), ++runs;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < seconds) {
    const Bytes input = mutate(corpus[rng() % corpus.size()], corpus, rng);
    LLVMFuzzerTestOneInput(input.data(), input.size());
    ++runs;
  }
  std::printf("%s: %zu inputs from %zu seeds in %.0f s, no crash and no sanitizer report\n", argv[0], runs,
              corpus.size(), seconds);
  return 0;
}
