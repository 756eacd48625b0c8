#include "nn/preprocess/clip_tokenizer.h"

#include <gtest/gtest.h>

#include <zlib.h>

#include <fstream>

#include "core/error.h"
#include "golden.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;

const ClipTokenizer& golden_tokenizer() {
  static const ClipTokenizer tokenizer = ClipTokenizer::load(golden_dir("clip_tokenizer") / "bpe_simple_vocab_16e6.txt.gz");
  return tokenizer;
}

TEST(ClipTokenizer, RawIdsMatchOpenaiOnAllGoldenPrompts) {
  const auto cases = read_json_file(golden_dir("clip_tokenizer") / "tokens.json").at("cases");
  ASSERT_EQ(cases.size(), 10u);
  for (const auto& c : cases) {
    const auto expected = c.at("ids").get<std::vector<int64_t>>();
    EXPECT_EQ(golden_tokenizer().encode(c.at("text").get<std::string>()), expected) << c.at("text");
  }
}

TEST(ClipTokenizer, Sd15InputIdsTruncateAndPad) {
  const auto cases = read_json_file(golden_dir("clip_tokenizer") / "tokens.json").at("cases");
  std::vector<std::string> prompts;
  for (const auto& c : cases) prompts.push_back(c.at("text").get<std::string>());
  const torch::Tensor ids = golden_tokenizer().input_ids(prompts);
  const torch::Tensor expected = golden_tensors("clip_tokenizer", "input_ids")["input_ids"];
  ASSERT_EQ(ids.sizes(), expected.sizes());
  for (int64_t i = 0; i < ids.size(0); ++i) EXPECT_TRUE(torch::equal(ids[i], expected[i])) << "prompt " << i;
  // Case 1 is Unique3D's 80-token negative prompt: cut to 75 tokens, the end token in the last slot.
  EXPECT_EQ(cases[1].at("n_tokens").get<int>(), 80);
  EXPECT_EQ(ids[1][76].item<int64_t>(), ClipTokenizer::kEndOfText);
}

TEST(ClipTokenizer, ReadsPlainMergesTextAndRejectsShortFiles) {
  // A diffusers tokenizer/merges.txt holds the same lines uncompressed.
  const auto dir = std::filesystem::temp_directory_path() / "u3d_clip_merges";
  std::filesystem::create_directories(dir);
  gzFile gz = gzopen((golden_dir("clip_tokenizer") / "bpe_simple_vocab_16e6.txt.gz").c_str(), "rb");
  ASSERT_NE(gz, nullptr);
  std::string text;
  char buffer[1 << 16];
  for (int n; (n = gzread(gz, buffer, sizeof(buffer))) > 0;) text.append(buffer, size_t(n));
  gzclose(gz);
  std::ofstream(dir / "merges.txt", std::ios::binary) << text;
  EXPECT_EQ(ClipTokenizer::load(dir / "merges.txt").encode("4views, multiview"),
            (std::vector<int64_t>{275, 2758, 267, 3947, 1093}));

  std::ofstream(dir / "short.txt") << "#version: 0.2\ni n\nt h\n";
  EXPECT_THROW(ClipTokenizer::load(dir / "short.txt"), u3d::Error);
  EXPECT_THROW(ClipTokenizer::load(dir / "missing.txt.gz"), u3d::Error);
  std::filesystem::remove_all(dir);
}

// Python's html.unescape rules beyond the golden prompts: numeric references (decimal, hex, the
// Windows-1252 range), legacy names without a semicolon, and text that only looks like a reference.
TEST(ClipTokenizer, UnescapesHtmlReferencesAsPython) {
  const ClipTokenizer& t = golden_tokenizer();
  EXPECT_EQ(t.encode("&#65;&#x42;c"), t.encode("abc"));
  EXPECT_EQ(t.encode("&#128; &#x80"), t.encode("\u20ac \u20ac"));
  EXPECT_EQ(t.encode("tom &ampjerry &lt3"), t.encode("tom &jerry <3"));
  EXPECT_EQ(t.encode("&#38;amp;"), t.encode("&"));  // unescaped twice
  // Not references: they stay as typed, so they split into the same pieces as with spaces.
  EXPECT_EQ(t.encode("&#x &apos"), t.encode("&# x & apos"));
  EXPECT_NE(t.encode("&apos;"), t.encode("& apos;"));
}

TEST(ClipTokenizer, RejectsInvalidUtf8) { EXPECT_THROW(golden_tokenizer().encode("bad \xff byte"), u3d::Error); }

}  // namespace
}  // namespace u3d::nn
