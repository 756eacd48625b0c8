#include "nn/preprocess/clip_tokenizer.h"

#include <unicode/uchar.h>
#include <unicode/ustring.h>
#include <unicode/utf16.h>
#include <unicode/utf8.h>
#include <zlib.h>

#include <algorithm>
#include <climits>

#include "core/error.h"

namespace u3d::nn {

namespace {

using CodePoints = std::u32string;

constexpr int kMerges = 49152 - 256 - 2;  // merges used: lines 2..48895 of the file

std::string read_maybe_gzipped(const std::filesystem::path& path) {
  // gzread passes files that are not gzip through unchanged, so merges.txt reads the same way.
  gzFile file = gzopen(path.c_str(), "rb");
  if (!file) throw Error("CLIP tokenizer: cannot open " + path.string());
  std::string text;
  char buffer[1 << 16];
  int n = 0;
  while ((n = gzread(file, buffer, sizeof(buffer))) > 0) text.append(buffer, static_cast<size_t>(n));
  const bool failed = n < 0;
  gzclose(file);
  if (failed) throw Error("CLIP tokenizer: " + path.string() + " is not a readable gzip or text file");
  return text;
}

void append_utf8(std::string& out, char32_t c) {
  char bytes[U8_MAX_LENGTH];
  int32_t n = 0;  // every code point here is a scalar value (surrogates become U+FFFD when unescaping)
  U8_APPEND_UNSAFE(reinterpret_cast<uint8_t*>(bytes), n, static_cast<UChar32>(c));
  out.append(bytes, static_cast<size_t>(n));
}

std::string to_utf8(const CodePoints& text, size_t begin, size_t end) {
  std::string out;
  for (size_t i = begin; i < end; ++i) append_utf8(out, text[i]);
  return out;
}

CodePoints from_utf8(const std::string& text) {
  CodePoints out;
  const auto* s = reinterpret_cast<const uint8_t*>(text.data());
  const auto length = static_cast<int32_t>(text.size());
  for (int32_t i = 0; i < length;) {
    UChar32 c = 0;
    U8_NEXT(s, i, length, c);
    if (c < 0) throw Error("CLIP tokenizer: the prompt is not valid UTF-8");
    out.push_back(static_cast<char32_t>(c));
  }
  return out;
}

// GPT-2's byte -> unicode table: printable Latin-1 bytes map to themselves, the other 68 bytes to
// U+0100 onwards in byte order. Returned in vocabulary order (the printable ones first).
std::vector<std::pair<int, char32_t>> byte_symbols_in_vocab_order() {
  std::vector<std::pair<int, char32_t>> order;
  auto printable = [](int b) { return (b >= 0x21 && b <= 0x7E) || (b >= 0xA1 && b <= 0xAC) || (b >= 0xAE && b <= 0xFF); };
  for (int b = 0; b < 256; ++b)
    if (printable(b)) order.emplace_back(b, static_cast<char32_t>(b));
  char32_t next = 0x100;
  for (int b = 0; b < 256; ++b)
    if (!printable(b)) order.emplace_back(b, next++);
  return order;
}

// Python's str.isspace: Unicode White_Space plus the information separators U+001C..U+001F.
bool py_isspace(char32_t c) { return u_isUWhiteSpace(static_cast<UChar32>(c)) || (c >= 0x1C && c <= 0x1F); }

bool is_letter(char32_t c) {
  const int8_t t = u_charType(static_cast<UChar32>(c));
  return t == U_UPPERCASE_LETTER || t == U_LOWERCASE_LETTER || t == U_TITLECASE_LETTER || t == U_MODIFIER_LETTER ||
         t == U_OTHER_LETTER;
}

bool is_number(char32_t c) {
  const int8_t t = u_charType(static_cast<UChar32>(c));
  return t == U_DECIMAL_DIGIT_NUMBER || t == U_LETTER_NUMBER || t == U_OTHER_NUMBER;
}

bool is_white_space(char32_t c) { return u_isUWhiteSpace(static_cast<UChar32>(c)); }

bool starts_with(const CodePoints& text, size_t at, std::u32string_view prefix) {
  return text.compare(at, prefix.size(), prefix) == 0;
}

// Python's html.unescape for numeric references; the code points Python drops come back empty.
CodePoints numeric_reference(uint64_t value) {
  // Windows-1252 for 0x80..0x9F, as the HTML5 spec; the five bytes it leaves undefined stay themselves.
  static constexpr char32_t kCp1252[32] = {0x20AC, 0x81,   0x201A, 0x0192, 0x201E, 0x2026, 0x2020, 0x2021,
                                           0x02C6, 0x2030, 0x0160, 0x2039, 0x0152, 0x8D,   0x017D, 0x8F,
                                           0x90,   0x2018, 0x2019, 0x201C, 0x201D, 0x2022, 0x2013, 0x2014,
                                           0x02DC, 0x2122, 0x0161, 0x203A, 0x0153, 0x9D,   0x017E, 0x0178};
  if (value == 0) return U"\uFFFD";
  if (value == 0x0D) return U"\r";
  if (value >= 0x80 && value <= 0x9F) return CodePoints(1, kCp1252[value - 0x80]);
  if ((value >= 0xD800 && value <= 0xDFFF) || value > 0x10FFFF) return U"\uFFFD";
  const auto c = static_cast<char32_t>(value);
  const bool dropped = (c >= 0x1 && c <= 0x8) || c == 0xB || (c >= 0xE && c <= 0x1F) || (c >= 0x7F && c <= 0x9F) ||
                       (c >= 0xFDD0 && c <= 0xFDEF) || (c & 0xFFFE) == 0xFFFE;
  return dropped ? CodePoints() : CodePoints(1, c);
}

// One pass of Python's html.unescape (named references: see the header).
CodePoints html_unescape(const CodePoints& text) {
  struct Named {
    std::u32string_view name;
    char32_t value;
    bool legacy;  // also recognised without the semicolon
  };
  static constexpr Named kNamed[] = {{U"amp", U'&', true},   {U"lt", U'<', true},    {U"gt", U'>', true},
                                     {U"quot", U'"', true},  {U"apos", U'\'', false}, {U"nbsp", 0xA0, true}};
  CodePoints out;
  for (size_t i = 0; i < text.size();) {
    if (text[i] != U'&') {
      out.push_back(text[i++]);
      continue;
    }
    size_t j = i + 1;
    if (j < text.size() && text[j] == U'#') {
      const bool hex = j + 1 < text.size() && (text[j + 1] == U'x' || text[j + 1] == U'X');
      size_t k = j + (hex ? 2 : 1);
      const size_t digits_begin = k;
      uint64_t value = 0;
      for (; k < text.size(); ++k) {
        const char32_t c = text[k];
        int digit = -1;
        if (c >= U'0' && c <= U'9') digit = int(c - U'0');
        else if (hex && c >= U'a' && c <= U'f') digit = int(c - U'a') + 10;
        else if (hex && c >= U'A' && c <= U'F') digit = int(c - U'A') + 10;
        if (digit < 0) break;
        value = std::min<uint64_t>(value * (hex ? 16 : 10) + uint64_t(digit), uint64_t{0x110000});
      }
      if (k == digits_begin) {  // "&#" without digits stays as it is
        out.push_back(text[i++]);
        continue;
      }
      if (k < text.size() && text[k] == U';') ++k;
      out += numeric_reference(value);
      i = k;
      continue;
    }
    // A name: up to 32 characters other than tab, newline, form feed, space, '<', '&', '#', ';'.
    size_t k = j;
    while (k < text.size() && k - j < 32 && !(text[k] == U'\t' || text[k] == U'\n' || text[k] == U'\f' ||
                                              text[k] == U' ' || text[k] == U'<' || text[k] == U'&' ||
                                              text[k] == U'#' || text[k] == U';'))
      ++k;
    const std::u32string_view name(text.data() + j, k - j);
    bool replaced = false;
    if (k < text.size() && text[k] == U';') {
      for (const auto& e : kNamed)
        if (name == e.name) {
          out.push_back(e.value);
          i = k + 1;
          replaced = true;
          break;
        }
    }
    // Without a semicolon: the longest legacy name that prefixes the text.
    for (size_t len = name.size(); !replaced && len >= 2; --len)
      for (const auto& e : kNamed)
        if (e.legacy && name.substr(0, len) == e.name) {
          out.push_back(e.value);
          i = j + len;
          replaced = true;
          break;
        }
    if (!replaced) out.push_back(text[i++]);
  }
  return out;
}

CodePoints py_strip(const CodePoints& text) {
  size_t begin = 0, end = text.size();
  while (begin < end && py_isspace(text[begin])) ++begin;
  while (end > begin && py_isspace(text[end - 1])) --end;
  return text.substr(begin, end - begin);
}

CodePoints collapse_white_space(const CodePoints& text) {
  CodePoints out;
  for (size_t i = 0; i < text.size();) {
    if (!is_white_space(text[i])) {
      out.push_back(text[i++]);
      continue;
    }
    while (i < text.size() && is_white_space(text[i])) ++i;
    out.push_back(U' ');
  }
  return out;
}

// Unicode full lowercase mapping (Python's str.lower, Final_Sigma included) through ICU's root locale.
CodePoints lowercase(const CodePoints& text) {
  std::u16string utf16;
  for (char32_t c : text) {
    UChar units[2];
    int32_t n = 0;
    U16_APPEND_UNSAFE(units, n, static_cast<UChar32>(c));
    utf16.append(units, units + n);
  }
  std::u16string lower(utf16.size() * 3 + 1, u'\0');
  UErrorCode status = U_ZERO_ERROR;
  const int32_t n = u_strToLower(lower.data(), int32_t(lower.size()), utf16.data(), int32_t(utf16.size()), "", &status);
  if (U_FAILURE(status)) throw Error(std::string("CLIP tokenizer: lowercasing failed: ") + u_errorName(status));
  CodePoints out;
  for (int32_t i = 0; i < n;) {
    UChar32 c = 0;
    U16_NEXT(lower.data(), i, n, c);
    out.push_back(static_cast<char32_t>(c));
  }
  return out;
}

CodePoints normalise(const std::string& text) {
  CodePoints t = html_unescape(html_unescape(from_utf8(text)));
  t = py_strip(collapse_white_space(py_strip(t)));
  return lowercase(t);
}

// The pieces of the pre-tokenization pattern, as [begin, end) ranges.
std::vector<std::pair<size_t, size_t>> pre_tokenize(const CodePoints& text) {
  static constexpr std::u32string_view kSpecials[] = {U"<|startoftext|>", U"<|endoftext|>"};
  static constexpr std::u32string_view kContractions[] = {U"'s", U"'t", U"'re", U"'ve", U"'m", U"'ll", U"'d"};
  std::vector<std::pair<size_t, size_t>> pieces;
  for (size_t i = 0; i < text.size();) {
    size_t end = i;
    for (auto s : kSpecials)
      if (end == i && starts_with(text, i, s)) end = i + s.size();
    for (auto s : kContractions)
      if (end == i && starts_with(text, i, s)) end = i + s.size();
    if (end == i && is_letter(text[i]))
      while (end < text.size() && is_letter(text[end])) ++end;
    if (end == i && is_number(text[i])) end = i + 1;
    if (end == i && !is_white_space(text[i]))
      while (end < text.size() && !is_white_space(text[end]) && !is_letter(text[end]) && !is_number(text[end])) ++end;
    if (end == i) {
      ++i;  // whitespace: not part of any piece
      continue;
    }
    pieces.emplace_back(i, end);
    i = end;
  }
  return pieces;
}

}  // namespace

ClipTokenizer ClipTokenizer::load(const std::filesystem::path& merges_file) {
  const std::string text = read_maybe_gzipped(merges_file);
  std::vector<std::string> merges;
  size_t line_begin = text.find('\n');  // line 1 is the "#version" header
  while (line_begin != std::string::npos && merges.size() < size_t(kMerges)) {
    ++line_begin;
    size_t line_end = text.find('\n', line_begin);
    std::string line = text.substr(line_begin, line_end == std::string::npos ? std::string::npos : line_end - line_begin);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    merges.push_back(std::move(line));
    line_begin = line_end;
  }
  if (merges.size() < size_t(kMerges) ||
      std::any_of(merges.begin(), merges.end(), [](const std::string& m) { return m.find(' ') == std::string::npos; }))
    throw Error("CLIP tokenizer: " + merges_file.string() + " does not hold " + std::to_string(kMerges) +
                " merges (one \"a b\" pair per line after a header line)");
  return ClipTokenizer(merges);
}

ClipTokenizer::ClipTokenizer(const std::vector<std::string>& merges) {
  byte_symbol_.resize(256);
  std::vector<std::string> base;
  for (const auto& [byte, symbol] : byte_symbols_in_vocab_order()) {
    std::string utf8;
    append_utf8(utf8, symbol);
    byte_symbol_[size_t(byte)] = utf8;
    base.push_back(utf8);
  }
  int64_t id = 0;
  for (const auto& s : base) ids_.emplace(s, id++);
  for (const auto& s : base) ids_.emplace(s + "</w>", id++);
  for (size_t rank = 0; rank < merges.size(); ++rank) {
    const std::string& m = merges[rank];
    const size_t space = m.find(' ');
    ids_.emplace(m.substr(0, space) + m.substr(space + 1), id++);
    merge_rank_.emplace(m, int(rank));
  }
  ids_.emplace("<|startoftext|>", kStartOfText);
  ids_.emplace("<|endoftext|>", kEndOfText);
}

std::vector<int64_t> ClipTokenizer::bpe(const std::string& piece) const {
  if (piece == "<|startoftext|>") return {kStartOfText};
  if (piece == "<|endoftext|>") return {kEndOfText};
  std::vector<std::string> word;
  for (unsigned char byte : piece) word.push_back(byte_symbol_[byte]);
  word.back() += "</w>";
  while (word.size() > 1) {
    int best = INT_MAX;
    size_t best_at = 0;
    for (size_t i = 0; i + 1 < word.size(); ++i) {
      auto it = merge_rank_.find(word[i] + " " + word[i + 1]);
      if (it != merge_rank_.end() && it->second < best) best = it->second, best_at = i;
    }
    if (best == INT_MAX) break;
    // Merge every occurrence of the best pair, left to right.
    const std::string first = word[best_at], second = word[best_at + 1];
    std::vector<std::string> merged;
    for (size_t i = 0; i < word.size();) {
      if (i + 1 < word.size() && word[i] == first && word[i + 1] == second) {
        merged.push_back(first + second);
        i += 2;
      } else {
        merged.push_back(word[i++]);
      }
    }
    word = std::move(merged);
  }
  std::vector<int64_t> ids;
  for (const auto& token : word) ids.push_back(ids_.at(token));
  return ids;
}

std::vector<int64_t> ClipTokenizer::encode(const std::string& text) const {
  const CodePoints normalised = normalise(text);
  std::vector<int64_t> ids;
  for (const auto& [begin, end] : pre_tokenize(normalised)) {
    const auto piece = bpe(to_utf8(normalised, begin, end));
    ids.insert(ids.end(), piece.begin(), piece.end());
  }
  return ids;
}

torch::Tensor ClipTokenizer::input_ids(const std::vector<std::string>& prompts) const {
  torch::Tensor out = torch::full({int64_t(prompts.size()), kContextLength}, kEndOfText, torch::kLong);
  auto rows = out.accessor<int64_t, 2>();
  for (size_t p = 0; p < prompts.size(); ++p) {
    const auto ids = encode(prompts[p]);
    rows[int64_t(p)][0] = kStartOfText;
    const size_t kept = std::min(ids.size(), size_t(kContextLength - 2));
    for (size_t i = 0; i < kept; ++i) rows[int64_t(p)][int64_t(i) + 1] = ids[i];
  }
  return out;
}

}  // namespace u3d::nn
