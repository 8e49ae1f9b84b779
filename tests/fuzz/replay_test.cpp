// Every seed (corpus/<harness>/) and every regression input (regressions/<harness>/) through its harness's
// fuzz_one(), in a normal build: what a fuzzer once found stays fixed without clang or libFuzzer. A finding
// aborts the test binary with the harness's message (the file name is printed first).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "harnesses.hpp"

namespace {

using FuzzOne = int (*)(const uint8_t*, std::size_t);

struct Harness {
    const char* name;
    FuzzOne fn;
};

#define SOFTECAT_FUZZ_ENTRY(n) Harness{#n, &fuzz::n::fuzz_one},
const Harness kHarnesses[] = {SOFTECAT_FUZZ_HARNESSES(SOFTECAT_FUZZ_ENTRY)};
#undef SOFTECAT_FUZZ_ENTRY

std::vector<std::filesystem::path> inputs(const std::string& sub, const std::string& harness) {
    std::vector<std::filesystem::path> files;
    const std::filesystem::path dir = std::filesystem::path(SOFTECAT_FUZZ_DIR) / sub / harness;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec))
        if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

std::size_t replay(const Harness& h, const std::string& sub) {
    std::size_t n = 0;
    for (const auto& f : inputs(sub, h.name)) {
        std::ifstream in(f, std::ios::binary);
        const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
        std::fprintf(stderr, "%s\n", f.string().c_str());  // names the input if the harness aborts
        EXPECT_EQ(h.fn(bytes.data(), bytes.size()), 0) << f;
        ++n;
    }
    return n;
}

class Replay : public ::testing::TestWithParam<Harness> {};

TEST_P(Replay, EveryCorpusInputRunsClean) {
    // Each harness has a seed corpus from real traffic and real files (tests/fuzz/make_corpus.py).
    EXPECT_GT(replay(GetParam(), "corpus"), 0u) << "no seed corpus for " << GetParam().name;
}

TEST_P(Replay, EveryRegressionInputRunsClean) {
    replay(GetParam(), "regressions");
}

TEST(Replay, EmptyAndTinyInputsRunClean) {
    for (const Harness& h : kHarnesses)
        for (std::size_t n = 0; n < 4; ++n) {
            const uint8_t zeros[4] = {};
            const uint8_t ones[4] = {0xFF, 0xFF, 0xFF, 0xFF};
            EXPECT_EQ(h.fn(zeros, n), 0) << h.name;
            EXPECT_EQ(h.fn(ones, n), 0) << h.name;
        }
}

INSTANTIATE_TEST_SUITE_P(Harnesses, Replay, ::testing::ValuesIn(kHarnesses),
                         [](const ::testing::TestParamInfo<Harness>& i) {
                             return std::string(i.param.name);
                         });

}  // namespace
