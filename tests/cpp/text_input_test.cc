#include "text_input.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "simloop/errors.hpp"
#include "simloop/scenario.hpp"

namespace simloop::detail {
namespace {

std::string dotted(std::size_t parts, const std::string& part = "a") {
  std::string key = part;
  for (std::size_t i = 1; i < parts; ++i) key += "." + part;
  return key;
}

std::string message_of(const std::string& text) {
  try {
    check_toml_key_parts(text, "s.toml");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(TomlKeyParts, KeysUpToTheLimitPassInEveryForm) {
  for (const std::string& text : {"[" + dotted(kMaxTomlKeyParts) + "]\n", "[[" + dotted(kMaxTomlKeyParts) + "]]\n",
                                  dotted(kMaxTomlKeyParts) + " = 1\n", "x = {" + dotted(kMaxTomlKeyParts) + " = 1}\n",
                                  "[" + dotted(kMaxTomlKeyParts, "\"q.q\"") + "]\n"}) {
    EXPECT_EQ(message_of(text), "") << text.substr(0, 40);
  }
}

TEST(TomlKeyParts, OnePartMoreIsRefusedWhereTheKeyBegins) {
  const std::string key = dotted(kMaxTomlKeyParts + 1);
  EXPECT_EQ(message_of("name = \"x\"\n\n[" + key + "]\n"),
            "s.toml:3:2: a key of more than 64 dotted parts (a.b.c has 3); a scenario's keys have at most 2");
  EXPECT_NE(message_of("  " + key + " = 1\n"), "");
  EXPECT_NE(message_of("x = {y = 2, " + key + " = 1}\n"), "");
  EXPECT_NE(message_of("['a' . \"b\" . " + dotted(kMaxTomlKeyParts - 1, "'c'") + "]\n"), "");
}

TEST(TomlKeyParts, ValuesWithDotsAreNotKeys) {
  std::string floats = "qpos = [";
  for (int i = 0; i < 1000; ++i) floats += "0.5, ";
  floats += "1.5]\nname = \"" + dotted(1000) + "\"\nother = '" + dotted(1000) + "'\n";
  EXPECT_EQ(message_of(floats), "");
}

TEST(TomlKeyParts, AFiftyThousandPartHeaderIsRefusedNotAStackOverflow) {
  const std::string text = "[" + dotted(50000) + "]\nb = 1\n";
  EXPECT_THROW((void)Scenario::from_toml_string(text, "dd.toml"), InvalidArgument);
}

TEST(ReadLine, StopsAtTheLimitNamingTheLine) {
  std::istringstream in("ab\n" + std::string(100, 'x') + "\n");
  std::string line;
  ASSERT_TRUE(read_line(in, line, 10, "u.csv", 1));
  EXPECT_EQ(line, "ab");
  try {
    (void)read_line(in, line, 10, "u.csv", 2);
    FAIL() << "a 100-byte line passed a 10-byte limit";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("u.csv:2: a line longer than"), std::string::npos) << e.what();
  }
}

TEST(ReadLine, ALastLineWithoutANewlineIsALine) {
  std::istringstream in("a\nb");
  std::string line;
  ASSERT_TRUE(read_line(in, line, 10, "u.csv", 1));
  ASSERT_TRUE(read_line(in, line, 10, "u.csv", 2));
  EXPECT_EQ(line, "b");
  EXPECT_FALSE(read_line(in, line, 10, "u.csv", 3));
}

TEST(ReadTextFile, ReadsWholeFilesAndRefusesLargerOnes) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "simloop_text_input_test.toml";
  std::ofstream(file, std::ios::binary) << std::string(200000, 'x');
  EXPECT_EQ(read_text_file(file, 200000, "a scenario file").size(), 200000u);
  EXPECT_THROW((void)read_text_file(file, 199999, "a scenario file"), InvalidArgument);
  std::filesystem::remove(file);
  EXPECT_THROW((void)read_text_file(file, 10, "a scenario file"), IoError);
  EXPECT_THROW((void)read_text_file(std::filesystem::temp_directory_path(), 10, "a scenario file"), IoError);
  EXPECT_THROW((void)read_text_file(std::string("a\0b", 3), 10, "a scenario file"), InvalidArgument);
}

TEST(QuotedValue, EscapesAndCuts) {
  EXPECT_EQ(quoted_value("a'b\\c\x1b"), "'a\\'b\\\\c\\x1b'");
  EXPECT_EQ(quoted_value(std::string(50, 'z'), 3), "'zzz' (3 of its 50 bytes)");
  EXPECT_EQ(one_line("a\x1b]0;t\x07\nb\tc"), "a\\x1b]0;t\\x07; b\tc");
}

}  // namespace
}  // namespace simloop::detail
