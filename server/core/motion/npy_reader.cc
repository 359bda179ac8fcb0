#include "server/core/motion/npy_reader.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace modskill {
namespace {

constexpr int64_t kInt64Max = std::numeric_limits<int64_t>::max();
constexpr absl::string_view kNpyMagic("\x93NUMPY", 6);
// NumPy's NPY_MAXDIMS is 32 (64 since NumPy 2); more is certainly a damaged header.
constexpr size_t kMaxDimensions = 64;

// The header length is little-endian. Callers have checked that `at` + width lies inside `bytes`.
uint64_t LoadLittleEndian(absl::string_view bytes, size_t at, int width) {
  uint64_t value = 0;
  for (int i = width - 1; i >= 0; --i) {
    value = (value << 8) | static_cast<unsigned char>(bytes[at + i]);
  }
  return value;
}

// True when [offset, offset + length) lies inside [0, limit), without overflowing.
bool Fits(uint64_t offset, uint64_t length, uint64_t limit) {
  return offset <= limit && length <= limit - offset;
}

// Header text and stray bytes for messages: printable ASCII as is, the rest as \xNN.
std::string Printable(absl::string_view bytes) {
  std::string shown;
  for (char c : bytes) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7F) {
      shown.push_back(c);
    } else {
      absl::StrAppendFormat(&shown, "\\x%02x", u);
    }
  }
  return shown;
}

absl::Status WithPrefix(const absl::Status& status, absl::string_view prefix) {
  return absl::Status(status.code(), absl::StrCat(prefix, ": ", status.message()));
}

// Shapes are shown the way NumPy prints them, so messages match what the user sees in Python.
std::string PythonShape(const std::vector<int64_t>& shape) {
  if (shape.size() == 1) return absl::StrCat("(", shape[0], ",)");
  return absl::StrCat("(", absl::StrJoin(shape, ", "), ")");
}

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<int64_t> shape;
};

// Parses the Python dict literal of a .npy header, e.g.
//   {'descr': '<f4', 'fortran_order': False, 'shape': (10, 72), }
// Only the literal forms NumPy writes are accepted, plus the "10L" longs of Python 2.
class HeaderDictParser {
 public:
  explicit HeaderDictParser(absl::string_view text) : text_(text) {}

  absl::StatusOr<NpyHeader> Parse() {
    NpyHeader header;
    bool has_descr = false, has_fortran_order = false, has_shape = false;
    SkipSpace();
    if (absl::Status s = Expect('{'); !s.ok()) return s;
    while (true) {
      SkipSpace();
      if (TryConsume('}')) break;
      const size_t key_pos = pos_;
      std::string key;
      if (absl::Status s = ParseString(&key); !s.ok()) return s;
      SkipSpace();
      if (absl::Status s = Expect(':'); !s.ok()) return s;
      SkipSpace();
      absl::Status value_status;
      bool* seen = nullptr;
      if (key == "descr") {
        seen = &has_descr;
        if (Peek() == '[') {
          return absl::UnimplementedError(
              "unsupported dtype: structured arrays (a descr that lists fields) are not "
              "supported");
        }
        value_status = ParseString(&header.descr);
      } else if (key == "fortran_order") {
        seen = &has_fortran_order;
        value_status = ParseBool(&header.fortran_order);
      } else if (key == "shape") {
        seen = &has_shape;
        value_status = ParseShape(&header.shape);
      } else {
        pos_ = key_pos;
        return Error(absl::StrCat("unexpected key '", key, "'"));
      }
      if (!value_status.ok()) return value_status;
      if (*seen) {
        pos_ = key_pos;
        return Error(absl::StrCat("key '", key, "' appears twice"));
      }
      *seen = true;
      SkipSpace();
      if (TryConsume(',')) continue;
      if (absl::Status s = Expect('}'); !s.ok()) return s;
      break;
    }
    SkipSpace();
    if (pos_ != text_.size()) return Error("unexpected text after the dict");
    if (!has_descr) return Error("key 'descr' is missing");
    if (!has_fortran_order) return Error("key 'fortran_order' is missing");
    if (!has_shape) return Error("key 'shape' is missing");
    return header;
  }

 private:
  char Peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }

  void SkipSpace() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\n' ||
                                   text_[pos_] == '\t' || text_[pos_] == '\r')) {
      ++pos_;
    }
  }

  bool TryConsume(char c) {
    if (Peek() != c || pos_ >= text_.size()) return false;
    ++pos_;
    return true;
  }

  absl::Status Expect(char c) {
    if (TryConsume(c)) return absl::OkStatus();
    return Error(absl::StrCat("expected '", absl::string_view(&c, 1), "'"));
  }

  absl::Status ParseString(std::string* out) {
    const char quote = Peek();
    if (quote != '\'' && quote != '"') return Error("expected a quoted string");
    ++pos_;
    out->clear();
    while (pos_ < text_.size() && text_[pos_] != quote) {
      if (text_[pos_] == '\\' && pos_ + 1 < text_.size()) ++pos_;
      out->push_back(text_[pos_++]);
    }
    if (pos_ >= text_.size()) return Error("unterminated string");
    ++pos_;
    return absl::OkStatus();
  }

  absl::Status ParseBool(bool* out) {
    const absl::string_view rest = text_.substr(pos_);
    if (absl::StartsWith(rest, "True")) {
      *out = true;
      pos_ += 4;
    } else if (absl::StartsWith(rest, "False")) {
      *out = false;
      pos_ += 5;
    } else {
      return Error("expected True or False");
    }
    return absl::OkStatus();
  }

  // A tuple of integers; "(5)" is taken as "(5,)" since no other reading makes sense.
  absl::Status ParseShape(std::vector<int64_t>* shape) {
    if (absl::Status s = Expect('('); !s.ok()) return s;
    shape->clear();
    SkipSpace();
    if (TryConsume(')')) return absl::OkStatus();
    while (true) {
      SkipSpace();
      const bool negative = TryConsume('-');
      if (!absl::ascii_isdigit(static_cast<unsigned char>(Peek()))) {
        return Error("expected an integer in the shape");
      }
      int64_t dimension = 0;
      while (absl::ascii_isdigit(static_cast<unsigned char>(Peek()))) {
        const int digit = text_[pos_++] - '0';
        if (dimension > (kInt64Max - digit) / 10) return Error("shape dimension overflows 64 bits");
        dimension = dimension * 10 + digit;
      }
      if (Peek() == 'L' || Peek() == 'l') ++pos_;  // Python 2 long.
      shape->push_back(negative ? -dimension : dimension);
      if (shape->size() > kMaxDimensions) {
        return Error(absl::StrCat("shape has more than ", kMaxDimensions, " dimensions"));
      }
      SkipSpace();
      if (TryConsume(',')) {
        SkipSpace();
        if (TryConsume(')')) return absl::OkStatus();
        continue;
      }
      return Expect(')');
    }
  }

  absl::Status Error(absl::string_view problem) const {
    constexpr size_t kShownChars = 160;
    const absl::string_view shown = text_.substr(0, kShownChars);
    return absl::InvalidArgumentError(absl::StrCat("bad header dict: ", problem, " at character ",
                                                   pos_, " of \"", Printable(shown),
                                                   text_.size() > kShownChars ? "...\"" : "\""));
  }

  absl::string_view text_;
  size_t pos_ = 0;
};

struct Dtype {
  char kind = 0;          // 'f', 'i', 'u', 'b', 'U' or 'S'.
  int64_t item_size = 0;  // Bytes per element.
  bool big_endian = false;
};

absl::StatusOr<Dtype> ParseDescr(const std::string& descr) {
  const auto unsupported = [&descr]() {
    return absl::UnimplementedError(absl::StrCat(
        "unsupported dtype '", descr,
        "' (supported: f4 f8 i1 i2 i4 i8 u1 u2 u4 u8 b1 in either byte order, and U and S "
        "strings)"));
  };
  if (descr.size() < 2) return unsupported();
  const char byte_order = descr[0];
  Dtype dtype;
  dtype.kind = descr[1];
  int64_t count = 0;
  const absl::string_view digits = absl::string_view(descr).substr(2);
  if (dtype.kind == 'O') {
    return absl::UnimplementedError(
        absl::StrCat("unsupported dtype '", descr,
                     "': it holds pickled Python objects, which cannot be read without Python"));
  }
  if ((byte_order != '<' && byte_order != '>' && byte_order != '|') || digits.empty() ||
      !std::all_of(digits.begin(), digits.end(),
                   [](char c) { return absl::ascii_isdigit(static_cast<unsigned char>(c)); }) ||
      !absl::SimpleAtoi(digits, &count)) {
    return unsupported();
  }
  dtype.big_endian = byte_order == '>';
  dtype.item_size = count;
  switch (dtype.kind) {
    case 'f':
      if (count == 4 || count == 8) return dtype;
      break;
    case 'i':
    case 'u':
      if (count == 1 || count == 2 || count == 4 || count == 8) return dtype;
      break;
    case 'b':
      if (count == 1) return dtype;
      break;
    case 'U':  // UTF-32 code units.
      if (count > kInt64Max / 4) break;
      dtype.item_size = count * 4;
      return dtype;
    case 'S':
      return dtype;
  }
  return unsupported();
}

uint64_t LoadBits(const unsigned char* bytes, int64_t width, bool big_endian) {
  uint64_t bits = 0;
  for (int64_t i = 0; i < width; ++i) {
    bits = (bits << 8) | bytes[big_endian ? i : width - 1 - i];
  }
  return bits;
}

double DecodeNumber(const Dtype& dtype, const unsigned char* bytes) {
  uint64_t bits = LoadBits(bytes, dtype.item_size, dtype.big_endian);
  switch (dtype.kind) {
    case 'f':
      if (dtype.item_size == 4) {
        const uint32_t bits32 = static_cast<uint32_t>(bits);
        float value;
        std::memcpy(&value, &bits32, sizeof(value));
        return value;
      } else {
        double value;
        std::memcpy(&value, &bits, sizeof(value));
        return value;
      }
    case 'i': {
      const int sign_bit = static_cast<int>(dtype.item_size * 8 - 1);
      if (sign_bit < 63 && ((bits >> sign_bit) & 1) != 0) bits |= ~uint64_t{0} << sign_bit;
      int64_t value;
      std::memcpy(&value, &bits, sizeof(value));
      return static_cast<double>(value);
    }
    case 'u':
      return static_cast<double>(bits);
    case 'b':
      return bits != 0 ? 1.0 : 0.0;
  }
  return 0.0;  // ParseDescr admits no other kind.
}

// Fortran order varies the first index fastest. Walk the C-order positions and gather.
std::vector<double> FortranToC(const std::vector<double>& fortran,
                               const std::vector<int64_t>& shape) {
  const int ndim = static_cast<int>(shape.size());
  std::vector<int64_t> fortran_stride(ndim);
  int64_t stride = 1;
  for (int d = 0; d < ndim; ++d) {
    fortran_stride[d] = stride;
    stride *= shape[d];
  }
  std::vector<int64_t> index(ndim, 0);
  std::vector<double> c_order(fortran.size());
  int64_t fortran_offset = 0;
  for (size_t i = 0; i < c_order.size(); ++i) {
    c_order[i] = fortran[fortran_offset];
    for (int d = ndim - 1; d >= 0; --d) {
      if (++index[d] < shape[d]) {
        fortran_offset += fortran_stride[d];
        break;
      }
      fortran_offset -= fortran_stride[d] * (shape[d] - 1);
      index[d] = 0;
    }
  }
  return c_order;
}

void AppendUtf8(uint32_t code_point, std::string* out) {
  if (code_point < 0x80) {
    out->push_back(static_cast<char>(code_point));
  } else if (code_point < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (code_point >> 6)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  } else if (code_point < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (code_point >> 12)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (code_point >> 18)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  }
}

// NumPy pads string elements with NULs and drops them on access; so do we.
absl::StatusOr<std::string> DecodeFirstString(const Dtype& dtype, absl::string_view element) {
  if (dtype.kind == 'S') {
    const size_t end = element.find_last_not_of('\0');
    return std::string(element.substr(0, end == absl::string_view::npos ? 0 : end + 1));
  }
  std::vector<uint32_t> code_points;
  for (size_t at = 0; at + 4 <= element.size(); at += 4) {
    code_points.push_back(static_cast<uint32_t>(LoadBits(
        reinterpret_cast<const unsigned char*>(element.data() + at), 4, dtype.big_endian)));
  }
  while (!code_points.empty() && code_points.back() == 0) code_points.pop_back();
  std::string utf8;
  for (uint32_t code_point : code_points) {
    if (code_point > 0x10FFFF || (code_point >= 0xD800 && code_point <= 0xDFFF)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("string holds invalid code point U+%X", code_point));
    }
    AppendUtf8(code_point, &utf8);
  }
  return utf8;
}
// The preamble: magic, version, header length. Splits the rest into header text and data.
struct NpySections {
  absl::string_view header;
  absl::string_view data;
};

absl::StatusOr<NpySections> SplitPreamble(absl::string_view bytes) {
  if (!LooksLikeNpy(bytes)) {
    return absl::InvalidArgumentError(absl::StrCat("not a .npy array: bad magic \"",
                                                   Printable(bytes.substr(0, 6)),
                                                   "\" (expected \"\\x93NUMPY\")"));
  }
  if (bytes.size() < 8) return absl::DataLossError("truncated inside the .npy preamble");
  const int major = static_cast<unsigned char>(bytes[6]);
  const int minor = static_cast<unsigned char>(bytes[7]);
  if ((major < 1 || major > 3) || minor != 0) {
    return absl::UnimplementedError(absl::StrCat(".npy format version ", major, ".", minor,
                                                 " is not supported (only 1.0, 2.0 and 3.0)"));
  }
  // Version 1.0 has a 16-bit header length; 2.0 and 3.0 a 32-bit one (3.0 allows UTF-8).
  const size_t length_width = major == 1 ? 2 : 4;
  const size_t header_start = 8 + length_width;
  if (bytes.size() < header_start) return absl::DataLossError("truncated inside the .npy preamble");
  const uint64_t header_size = LoadLittleEndian(bytes, 8, static_cast<int>(length_width));
  if (!Fits(header_start, header_size, bytes.size())) {
    return absl::DataLossError(absl::StrCat("header claims ", header_size, " bytes but only ",
                                            bytes.size() - header_start, " follow"));
  }
  return NpySections{bytes.substr(header_start, header_size),
                     bytes.substr(header_start + header_size)};
}

// The product of the shape, refused when a dimension is negative or the product (or its bytes)
// overflows 64 bits. A zero dimension makes the array empty however large the others are.
absl::StatusOr<int64_t> ElementCount(const NpyHeader& header, const Dtype& dtype) {
  bool has_zero_dimension = false;
  for (int64_t dimension : header.shape) {
    if (dimension < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("shape ", PythonShape(header.shape), " has a negative dimension"));
    }
    has_zero_dimension |= dimension == 0;
  }
  if (has_zero_dimension) return 0;
  int64_t count = 1;
  for (int64_t dimension : header.shape) {
    if (count > kInt64Max / dimension) {
      return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header.shape),
                                                     " has more elements than fit in 64 bits"));
    }
    count *= dimension;
  }
  if (dtype.item_size != 0 && count > kInt64Max / dtype.item_size) {
    return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header.shape), " of ",
                                                   header.descr,
                                                   " needs more bytes than fit in 64 bits"));
  }
  return count;
}

// What the header declares against the data that follows it and against the limits, before
// anything is allocated.
absl::Status CheckSizes(const NpyHeader& header, const Dtype& dtype, int64_t count,
                        absl::string_view data, const ResourceLimits& limits) {
  const uint64_t needed = static_cast<uint64_t>(count * dtype.item_size);
  if (data.size() != needed) {
    return absl::InvalidArgumentError(absl::StrCat("data is ", data.size(), " bytes but shape ",
                                                   PythonShape(header.shape), " of ",
                                                   header.descr, " needs ", needed));
  }
  // Motion matrices hold one row per frame: more rows than a clip may have frames is refused
  // here, before the conversion to double doubles the member's memory (a 117 KB archive of
  // 200,000 zero frames peaked at 196 MB through AddMotions without it).
  if (header.shape.size() >= 2 && header.shape[0] > limits.max_clip_frames) {
    return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header.shape), ": ", header.shape[0],
                                                   " frames, more than the limit of ", limits.max_clip_frames,
                                                   " (max_clip_frames)"));
  }
  // Numbers are held as doubles: a u1 array takes eight times its bytes in the file.
  const bool numeric = dtype.kind != 'U' && dtype.kind != 'S';
  if (numeric && count > limits.max_npz_member_bytes / static_cast<int64_t>(sizeof(double))) {
    return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header.shape), " holds ", count,
                                                   " numbers, more than the ", limits.max_npz_member_bytes,
                                                   " bytes as doubles allowed per array (max_npz_member_bytes)"));
  }
  return absl::OkStatus();
}

// The checked data as an NpyArray: the first element of a string array, or every number as a
// double in C order.
absl::StatusOr<NpyArray> DecodeArray(const NpyHeader& header, const Dtype& dtype, int64_t count,
                                     absl::string_view data) {
  NpyArray array;
  array.shape = header.shape;
  array.dtype = header.descr;
  if (dtype.kind == 'U' || dtype.kind == 'S') {
    if (count > 0) {
      absl::StatusOr<std::string> text =
          DecodeFirstString(dtype, data.substr(0, static_cast<size_t>(dtype.item_size)));
      if (!text.ok()) return text.status();
      array.text = *std::move(text);
    }
    return array;
  }
  array.data.resize(static_cast<size_t>(count));
  const auto* element = reinterpret_cast<const unsigned char*>(data.data());
  for (double& value : array.data) {
    value = DecodeNumber(dtype, element);
    element += dtype.item_size;
  }
  if (header.fortran_order && array.shape.size() >= 2) {
    array.data = FortranToC(array.data, array.shape);
  }
  return array;
}

absl::StatusOr<NpyArray> ParseNpyUnprefixed(absl::string_view bytes, const ResourceLimits& limits) {
  absl::StatusOr<NpySections> sections = SplitPreamble(bytes);
  if (!sections.ok()) return sections.status();
  absl::StatusOr<NpyHeader> header = HeaderDictParser(sections->header).Parse();
  if (!header.ok()) return header.status();
  absl::StatusOr<Dtype> dtype = ParseDescr(header->descr);
  if (!dtype.ok()) return dtype.status();
  absl::StatusOr<int64_t> count = ElementCount(*header, *dtype);
  if (!count.ok()) return count.status();
  if (absl::Status sizes = CheckSizes(*header, *dtype, *count, sections->data, limits); !sizes.ok()) {
    return sizes;
  }
  return DecodeArray(*header, *dtype, *count, sections->data);
}

}  // namespace

int64_t NpyArray::size() const {
  int64_t count = 1;
  for (int64_t dimension : shape) count *= dimension;
  return count;
}

bool LooksLikeNpy(absl::string_view bytes) { return absl::StartsWith(bytes, kNpyMagic); }

absl::StatusOr<NpyArray> ParseNpy(absl::string_view bytes, absl::string_view what, const ResourceLimits& limits) {
  absl::StatusOr<NpyArray> array = ParseNpyUnprefixed(bytes, limits);
  if (!array.ok()) return WithPrefix(array.status(), what);
  return array;
}

}  // namespace modskill
