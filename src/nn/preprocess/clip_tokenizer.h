#pragma once
// The CLIP byte-level BPE tokenizer (openai CLIP's simple_tokenizer, which transformers' CLIPTokenizer
// reproduces), and the 77-token input ids Stable Diffusion 1.x feeds its text encoder.
//
// Vocabulary (49,408 ids): the 256 byte symbols in GPT-2's byte->unicode order, the same 256 with the
// end-of-word mark "</w>", one id per merge of the merges file in file order (its lines 2..48,895),
// then <|startoftext|> 49406 and <|endoftext|> 49407. The merges come from openai's
// bpe_simple_vocab_16e6.txt.gz or from a diffusers folder's tokenizer/merges.txt (the same lines,
// uncompressed).
//
// Text normalisation, as simple_tokenizer.py with ftfy left out (ftfy.fix_text is not applied: text
// that ftfy would repair, such as mojibake, ligatures or fullwidth forms, tokenizes as it is):
//  - HTML character references are unescaped twice, as Python's html.unescape: numeric ones (&#38;,
//    &#x26;) fully, named ones only for amp, lt, gt, quot, apos and nbsp (Python knows all HTML5 names);
//  - leading and trailing whitespace is stripped, runs of Unicode White_Space become one space;
//  - the text is lowercased with Unicode's full case mapping (ICU, as Python's str.lower).
// Pre-tokenization: at each position the first of <|startoftext|>, <|endoftext|>, the contractions
// 's 't 're 've 'm 'll 'd, a run of letters (\p{L}), one number character (\p{N}), a run of anything
// else but whitespace; whitespace between pieces is dropped. Each piece's UTF-8 bytes become byte
// symbols, the last one marked end-of-word, and the adjacent pair with the lowest merge rank is merged
// until no pair is in the merge table.
#include <torch/torch.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

namespace u3d::nn {

class ClipTokenizer {
 public:
  static constexpr int64_t kStartOfText = 49406;
  static constexpr int64_t kEndOfText = 49407;  // also SD 1.x's padding id
  static constexpr int64_t kContextLength = 77;

  // Reads the merges from bpe_simple_vocab_16e6.txt.gz or merges.txt (gzip or plain text); an Error
  // names the file when it cannot be read or has fewer than 48,894 merges.
  static ClipTokenizer load(const std::filesystem::path& merges_file);

  // The BPE ids of `text` (UTF-8) without start/end tokens and without truncation. Invalid UTF-8 is an
  // Error.
  std::vector<int64_t> encode(const std::string& text) const;

  // SD 1.x text-encoder input: [<|startoftext|>, the first 75 ids, <|endoftext|>], padded to 77 with
  // <|endoftext|>. int64 [prompts.size(), 77].
  torch::Tensor input_ids(const std::vector<std::string>& prompts) const;

 private:
  explicit ClipTokenizer(const std::vector<std::string>& merges);
  std::vector<int64_t> bpe(const std::string& piece_utf8) const;

  std::unordered_map<std::string, int64_t> ids_;  // token (in the byte-symbol alphabet) -> id
  std::unordered_map<std::string, int> merge_rank_;  // "a b" -> rank
  std::vector<std::string> byte_symbol_;            // byte -> its symbol, UTF-8
};

}  // namespace u3d::nn
