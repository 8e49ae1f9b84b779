// The one lexer of the line-oriented formats (util/lex.hpp) and the bounded read of input files
// (util/input_file.hpp).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/temp_dir.hpp"
#include "util/dir_lock.hpp"
#include "util/input_file.hpp"
#include "util/lex.hpp"

namespace {

std::vector<std::string> texts(std::string_view line) {
    std::vector<std::string> out;
    for (const util::Word& w : util::split(line))
        out.push_back(w.text);
    return out;
}

using V = std::vector<std::string>;

TEST(Lex, WordsAreSeparatedByBlanks) {
    EXPECT_EQ(texts("  a\tbb  c\r"), (V{"a", "bb", "c"}));
    EXPECT_EQ(texts(""), V{});
    EXPECT_EQ(texts(" \t "), V{});
}

TEST(Lex, AWordBeginningWithHashOrSemicolonIsAComment) {
    EXPECT_EQ(texts("power 1 on # switch it on"), (V{"power", "1", "on"}));
    EXPECT_EQ(texts("; all comment"), V{});
    EXPECT_EQ(texts("a#b c;d"), (V{"a#b", "c;d"}));  // inside a word: part of it
    EXPECT_EQ(texts("\"# not a comment\" x"), (V{"# not a comment", "x"}));
}

TEST(Lex, QuotesJoinBlanksAndResolveEscapes) {
    EXPECT_EQ(texts(R"(config="my drive.conf" x)"), (V{"config=my drive.conf", "x"}));
    EXPECT_EQ(texts(R"("say \"hi\" \\ \t" 'single \n #')"), (V{"say \"hi\" \\ \t", "single \\n #"}));
    const auto w = util::split(R"(a "b")");
    EXPECT_FALSE(w[0].quoted);
    EXPECT_TRUE(w[1].quoted);
    EXPECT_EQ(w[1].begin, 2u);
    EXPECT_EQ(w[1].end, 5u);
    EXPECT_EQ(texts(R"("")"), V{""});
}

TEST(Lex, BadLinesAreRefusedWithAReason) {
    EXPECT_THROW(util::split(R"(a "open)"), util::LexError);
    EXPECT_THROW(util::split(R"(a 'open)"), util::LexError);
    EXPECT_THROW(util::split(R"("a\q")"), util::LexError);
    EXPECT_THROW(util::split(R"("a\)"), util::LexError);
    EXPECT_THROW(util::split(std::string("dev\0ice", 7)), util::LexError);
    EXPECT_THROW(util::split("a\x1b[2J"), util::LexError);
    EXPECT_THROW(util::split("\xC3("), util::LexError);  // broken UTF-8
    EXPECT_THROW(util::split("\xF5\x80\x80\x80"), util::LexError);
    EXPECT_EQ(texts("Gr\xC3\xB6\xC3\x9F"
                    "e"),
              V{"Gr\xC3\xB6\xC3\x9F"
                "e"});
    try {
        util::split("x \"open");
        FAIL();
    } catch (const util::LexError& e) {
        EXPECT_NE(std::string(e.what()).find("column 3"), std::string::npos) << e.what();
    }
}

TEST(Lex, ValueTextKeepsBareWordsOrOneQuotedWord) {
    EXPECT_EQ(util::value_text("  bare words  here # comment"), "bare words  here");
    EXPECT_EQ(util::value_text(R"( "a # b" ; c)"), "a # b");
    EXPECT_EQ(util::value_text("   "), "");
    EXPECT_EQ(util::value_text(R"("")"), "");
    EXPECT_THROW(util::value_text(R"("a" b)"), util::LexError);
}

TEST(Lex, TrimBlanksDropsSpaceTabAndCrAtBothEnds) {
    EXPECT_EQ(util::trim_blanks(" \t key = v \r"), "key = v");
    EXPECT_EQ(util::trim_blanks("a b"), "a b");
    EXPECT_EQ(util::trim_blanks(" \t\r "), "");
    EXPECT_EQ(util::trim_blanks("\nx\n"), "\nx\n");  // a newline is not a blank
}

TEST(Lex, KeyValue) {
    const auto kv = util::key_value("at=a:1");
    ASSERT_TRUE(kv);
    EXPECT_EQ(kv->first, "at");
    EXPECT_EQ(kv->second, "a:1");
    EXPECT_FALSE(util::key_value("=x"));
    EXPECT_FALSE(util::key_value("x="));
    EXPECT_FALSE(util::key_value("x"));
}

TEST(LexNumber, IntegersInTheTargetTypeWithRangeChecks) {
    EXPECT_EQ(util::number<int>("42"), 42);
    EXPECT_EQ(util::number<int>("-42"), -42);
    EXPECT_EQ(util::number<uint32_t>("0xFFFFFFFF"), 0xFFFFFFFFu);
    EXPECT_EQ(util::number<uint32_t>("0X1f"), 0x1Fu);
    EXPECT_EQ(util::number<int64_t>("-9223372036854775808"), INT64_MIN);
    EXPECT_FALSE(util::number<uint32_t>("0x100000000"));  // does not fit the type
    EXPECT_FALSE(util::number<int>("2147483648"));
    EXPECT_FALSE(util::number<int>("1e300"));  // the finding: no floating text into an int
    EXPECT_FALSE(util::number<int>("1.0"));
    EXPECT_FALSE(util::number<int>("+1"));
    EXPECT_FALSE(util::number<int>(" 1"));
    EXPECT_FALSE(util::number<int>("1 "));
    EXPECT_FALSE(util::number<int>(""));
    EXPECT_FALSE(util::number<int>("0x"));
    EXPECT_FALSE(util::number<int>("0x-1"));  // hexadecimal is never negative
    EXPECT_FALSE(util::number<int>("-0x1"));
    EXPECT_FALSE(util::number<unsigned>("-1"));
    EXPECT_FALSE(util::number<int>("-1", 0, 10));  // negative only where the range allows it
    EXPECT_EQ(util::number<int>("10", 0, 10), 10);
    EXPECT_FALSE(util::number<int>("11", 0, 10));
    int v = 7;
    EXPECT_EQ(util::parse_number("x", v, 0, 10), util::NumberError::NotANumber);
    EXPECT_EQ(util::parse_number("11", v, 0, 10), util::NumberError::OutOfRange);
    EXPECT_EQ(util::parse_number("99999999999999999999", v), util::NumberError::OutOfRange);
    EXPECT_EQ(v, 7);  // untouched on an error
}

TEST(LexNumber, FloatingPointIsFiniteAndInRange) {
    EXPECT_EQ(util::number<double>("0.25"), 0.25);
    EXPECT_EQ(util::number<double>("-1e3"), -1000.0);
    EXPECT_FALSE(util::number<double>("1e999"));
    EXPECT_FALSE(util::number<double>("inf"));
    EXPECT_FALSE(util::number<double>("nan"));
    EXPECT_FALSE(util::number<double>("0x10"));
    EXPECT_FALSE(util::number<double>("1.5", 0.0, 1.0));
    double d = 0;
    EXPECT_EQ(util::parse_number("1e999", d), util::NumberError::OutOfRange);
    EXPECT_EQ(util::parse_number("inf", d), util::NumberError::NotANumber);
}

TEST(LexNumber, OneWordingForRanges) {
    EXPECT_EQ(util::expected_number(0, 3), "an integer 0..3");
    EXPECT_EQ(util::expected_number<uint32_t>(0, 0xFFFFFFFF), "an integer 0..4294967295");
    EXPECT_EQ(util::expected_number(-1000.0, 1000.0), "-1000..1000");
    EXPECT_EQ(util::number_message("port", "9", 0, 3), "bad number '9' for port (expected an integer 0..3)");
}

TEST(InputFile, ReadsARegularFileWithinTheLimit) {
    test_support::TempDir dir;
    const auto p = dir.path / "f";
    std::ofstream(p) << "hello";
    EXPECT_EQ(util::read_input_file(p, 5, "test file"), "hello");
    EXPECT_EQ(util::read_input_bytes(p, 5, "test file").size(), 5u);
    EXPECT_THROW(util::read_input_file(p, 4, "test file"), util::InputFileError);
}

TEST(InputFile, RefusesDevicesFifosDirectoriesAndMissingFiles) {
    test_support::TempDir dir;
    EXPECT_THROW(util::read_input_file("/dev/zero", 1 << 20, "test file"), util::InputFileError);
    EXPECT_THROW(util::read_input_file("/dev/urandom", 1 << 20, "test file"), util::InputFileError);
    EXPECT_THROW(util::read_input_file(dir.path, 1 << 20, "test file"), util::InputFileError);
    EXPECT_THROW(util::read_input_file(dir.path / "none", 1 << 20, "test file"), util::InputFileError);
    const auto fifo = dir.path / "fifo";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    try {
        util::read_input_file(fifo, 1 << 20, "topology file");  // no writer: must not hang in open()
        FAIL();
    } catch (const util::InputFileError& e) {
        EXPECT_EQ(std::string(e.what()),
                  fifo.string() + ": not a regular file (a FIFO); the topology file must be a file");
    }
}

}  // namespace

namespace {

// Issue 24, finding 6: nothing stopped two devices or two processes from using one state directory.
TEST(DirLock, OneHolderPerStateDirectory) {
    test_support::TempDir dir;
    const auto state = dir.path / "drive1";
    {
        util::DirLock first(state);
        EXPECT_TRUE(first.held());
        EXPECT_TRUE(std::filesystem::is_directory(state));       // created as the device would
        EXPECT_THROW(util::DirLock{state}, util::DirLockError);  // a second device of this process
        const pid_t child = ::fork();                            // another process
        if (child == 0) {
            try {
                util::DirLock other(state);
            } catch (const util::DirLockError&) {
                ::_exit(0);
            }
            ::_exit(1);
        }
        int status = 0;
        ASSERT_EQ(::waitpid(child, &status, 0), child);
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    }
    util::DirLock again(state);  // released with the first
    EXPECT_TRUE(again.held());
}

}  // namespace
