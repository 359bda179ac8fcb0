// Parses BVH text: the HIERARCHY (joints, offsets, channels) and the MOTION frames into a BvhClip.
#include "server/core/motion/bvh_parser.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <new>
#include <system_error>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/core/motion/bvh_tokenizer.h"

namespace modskill {
namespace {

using bvh_internal::LineReader;
using bvh_internal::MatchHeader;
using bvh_internal::Quoted;
using bvh_internal::SplitTokens;
using bvh_internal::Token;
using bvh_internal::TokenReader;

constexpr double kDegreesToRadians = 3.14159265358979323846 / 180.0;
constexpr int kMaxChannelsPerJoint = 6;

enum class ChannelKind { kXposition, kYposition, kZposition, kXrotation, kYrotation, kZrotation };

struct ChannelName {
  const char* name;
  ChannelKind kind;
};
constexpr ChannelName kChannelNames[] = {
    {"Xposition", ChannelKind::kXposition}, {"Yposition", ChannelKind::kYposition},
    {"Zposition", ChannelKind::kZposition}, {"Xrotation", ChannelKind::kXrotation},
    {"Yrotation", ChannelKind::kYrotation}, {"Zrotation", ChannelKind::kZrotation},
};

bool IsPosition(ChannelKind kind) {
  return kind == ChannelKind::kXposition || kind == ChannelKind::kYposition ||
         kind == ChannelKind::kZposition;
}

// Axis 0, 1, 2 for X, Y, Z of either channel type.
int AxisOf(ChannelKind kind) {
  switch (kind) {
    case ChannelKind::kXposition:
    case ChannelKind::kXrotation:
      return 0;
    case ChannelKind::kYposition:
    case ChannelKind::kYrotation:
      return 1;
    case ChannelKind::kZposition:
    case ChannelKind::kZrotation:
      return 2;
  }
  return 0;
}

// Per-joint data the public struct does not carry.
struct JointChannels {
  int first_value = 0;  // column of the joint's first channel in a frame line
  std::vector<ChannelKind> kinds;
};

class BvhParser {
 public:
  BvhParser(absl::string_view text, absl::string_view file_name)
      : file_name_(file_name), lines_(text), tokens_(&lines_) {}

  absl::StatusOr<BvhClip> Parse() {
    if (absl::Status status = ParseHierarchy(); !status.ok()) return status;
    if (absl::Status status = ParseMotion(); !status.ok()) return status;
    return std::move(clip_);
  }

 private:
  absl::Status ErrorAt(int line, absl::string_view problem) const {
    return absl::InvalidArgumentError(absl::StrCat(file_name_, ":", line, ": ", problem));
  }

  // Where the text ended, for "missing ..." messages; line 1 for an empty text.
  int EndLine() const { return std::max(1, lines_.line_number()); }

  absl::Status ParseHierarchy() {
    Token token;
    if (!tokens_.Next(&token)) return ErrorAt(EndLine(), "empty file, missing HIERARCHY");
    if (!absl::EqualsIgnoreCase(token.text, "HIERARCHY")) {
      return ErrorAt(token.line, absl::StrCat("missing HIERARCHY, found ", Quoted(token.text)));
    }
    if (!tokens_.RestOfLine().empty()) {
      return ErrorAt(token.line, "unexpected text after HIERARCHY");
    }
    if (!tokens_.Next(&token)) return ErrorAt(EndLine(), "missing ROOT after HIERARCHY");
    if (!absl::EqualsIgnoreCase(token.text, "ROOT")) {
      return ErrorAt(token.line, absl::StrCat("expected ROOT, found ", Quoted(token.text)));
    }
    if (absl::Status status = ParseJointTree(token); !status.ok()) return status;

    if (!tokens_.Next(&token)) return ErrorAt(EndLine(), "missing MOTION section");
    if (absl::EqualsIgnoreCase(token.text, "MOTION")) {
      if (!tokens_.RestOfLine().empty()) return ErrorAt(token.line, "unexpected text after MOTION");
      return absl::OkStatus();
    }
    if (token.text == "}") {
      return ErrorAt(token.line, "unbalanced braces: '}' without a matching '{'");
    }
    if (absl::EqualsIgnoreCase(token.text, "ROOT")) {
      return ErrorAt(token.line, "more than one ROOT is not supported");
    }
    return ErrorAt(token.line, absl::StrCat("expected MOTION, found ", Quoted(token.text)));
  }

  // A joint whose "{" has been read but not yet its "}".
  struct OpenJoint {
    int joint = 0;
    int keyword_line = 0;
    bool has_offset = false;
    bool has_channels = false;
  };

  // Called with the ROOT keyword consumed; reads through the root's closing brace. Iterative,
  // with an explicit stack, so a deep chain cannot overflow the thread's stack.
  absl::Status ParseJointTree(const Token& root_keyword) {
    std::vector<OpenJoint> open;
    if (absl::Status status = OpenJointBlock(root_keyword, /*parent=*/-1, &open); !status.ok()) {
      return status;
    }
    while (!open.empty()) {
      const int depth = static_cast<int>(open.size()) - 1;
      const int joint = open[depth].joint;
      Token token;
      if (!tokens_.Next(&token)) {
        return UnclosedBlock(joint, open[depth].keyword_line, EndLine(), "the end");
      }
      if (token.text == "}") {
        if (!open[depth].has_offset) {
          return ErrorAt(open[depth].keyword_line,
                         absl::StrCat("joint ", clip_.joints[joint].name, " has no OFFSET"));
        }
        open.pop_back();
      } else if (absl::EqualsIgnoreCase(token.text, "OFFSET")) {
        if (open[depth].has_offset) return ErrorAt(token.line, "second OFFSET in one joint");
        open[depth].has_offset = true;
        if (absl::Status status = ParseOffset(token, &clip_.joints[joint].offset); !status.ok()) {
          return status;
        }
      } else if (absl::EqualsIgnoreCase(token.text, "CHANNELS")) {
        if (open[depth].has_channels) return ErrorAt(token.line, "second CHANNELS in one joint");
        open[depth].has_channels = true;
        if (absl::Status status = ParseChannels(token, joint); !status.ok()) return status;
      } else if (absl::EqualsIgnoreCase(token.text, "JOINT")) {
        if (absl::Status status = OpenJointBlock(token, joint, &open); !status.ok()) {
          return status;
        }
      } else if (absl::EqualsIgnoreCase(token.text, "End")) {
        if (absl::Status status = ParseEndSite(token, joint); !status.ok()) return status;
      } else if (absl::EqualsIgnoreCase(token.text, "MOTION")) {
        return UnclosedBlock(joint, open[depth].keyword_line, token.line, "MOTION");
      } else if (absl::EqualsIgnoreCase(token.text, "ROOT")) {
        return ErrorAt(token.line, "ROOT inside a joint block (more than one ROOT?)");
      } else {
        return ErrorAt(token.line, absl::StrCat("unexpected ", Quoted(token.text), " in joint ",
                                                clip_.joints[joint].name));
      }
    }
    return absl::OkStatus();
  }

  // Called with the ROOT/JOINT keyword consumed: reads the name and the "{", adds the joint
  // and pushes it onto `open`.
  absl::Status OpenJointBlock(const Token& keyword, int parent, std::vector<OpenJoint>* open) {
    // Some exporters put "{" on the name line, and a few allow spaces in names.
    std::vector<Token> name_tokens = tokens_.RestOfLine();
    const bool brace_on_name_line = !name_tokens.empty() && name_tokens.back().text == "{";
    if (brace_on_name_line) name_tokens.pop_back();
    if (name_tokens.empty()) {
      return ErrorAt(keyword.line, absl::StrCat(keyword.text, " without a name"));
    }
    std::string name;
    for (const Token& part : name_tokens) {
      if (absl::StrContains(part.text, '{') || absl::StrContains(part.text, '}')) {
        return ErrorAt(keyword.line, absl::StrCat("brace inside joint name ", Quoted(part.text)));
      }
      absl::StrAppend(&name, name.empty() ? "" : " ", part.text);
    }
    if (clip_.joints.size() >= static_cast<size_t>(kMaxBvhJoints)) {
      return ErrorAt(keyword.line, absl::StrCat("more than ", kMaxBvhJoints, " joints"));
    }
    if (auto [it, inserted] = line_by_name_.try_emplace(name, keyword.line); !inserted) {
      return ErrorAt(keyword.line, absl::StrCat("duplicate joint name ", Quoted(name),
                                                " (first defined on line ", it->second, ")"));
    }
    const int joint = static_cast<int>(clip_.joints.size());
    clip_.joints.emplace_back();
    clip_.joints.back().name = std::move(name);
    clip_.joints.back().parent = parent;
    channels_.emplace_back();

    if (!brace_on_name_line) {
      Token token;
      if (!tokens_.Next(&token)) return UnclosedBlock(joint, keyword.line, EndLine(), "the end");
      if (token.text != "{") {
        return ErrorAt(token.line,
                       absl::StrCat("expected '{' after ", keyword.text, " ",
                                    clip_.joints[joint].name, ", found ", Quoted(token.text)));
      }
    }
    open->push_back(OpenJoint{joint, keyword.line});
    return absl::OkStatus();
  }

  absl::Status UnclosedBlock(int joint, int open_line, int error_line, absl::string_view where) {
    return ErrorAt(error_line,
                   absl::StrFormat("unbalanced braces: block of joint %s (line %d) is not "
                                   "closed before %s",
                                   clip_.joints[joint].name, open_line, where));
  }

  // Called with "End" consumed.
  absl::Status ParseEndSite(const Token& end, int joint) {
    std::vector<Token> rest = tokens_.RestOfLine();
    const bool brace_on_line = !rest.empty() && rest.back().text == "{";
    if (brace_on_line) rest.pop_back();
    if (rest.size() != 1 || !absl::EqualsIgnoreCase(rest[0].text, "Site")) {
      return ErrorAt(end.line, "expected 'End Site'");
    }
    BvhJoint& owner = clip_.joints[joint];
    if (owner.has_end_site) {
      return ErrorAt(end.line, absl::StrCat("joint ", owner.name, " has a second End Site"));
    }
    owner.has_end_site = true;
    Token token;
    if (!brace_on_line) {
      if (!tokens_.Next(&token)) return UnclosedEndSite(end.line, EndLine());
      if (token.text != "{") {
        return ErrorAt(token.line,
                       absl::StrCat("expected '{' after End Site, found ", Quoted(token.text)));
      }
    }
    bool has_offset = false;
    while (true) {
      if (!tokens_.Next(&token)) return UnclosedEndSite(end.line, EndLine());
      if (token.text == "}") break;
      if (absl::EqualsIgnoreCase(token.text, "OFFSET") && !has_offset) {
        has_offset = true;
        if (absl::Status status = ParseOffset(token, &clip_.joints[joint].end_site_offset);
            !status.ok()) {
          return status;
        }
      } else if (absl::EqualsIgnoreCase(token.text, "MOTION")) {
        return UnclosedEndSite(end.line, token.line);
      } else {
        return ErrorAt(token.line, absl::StrCat("unexpected ", Quoted(token.text),
                                                " in End Site of ", owner.name));
      }
    }
    if (!has_offset) return ErrorAt(end.line, "End Site has no OFFSET");
    return absl::OkStatus();
  }

  absl::Status UnclosedEndSite(int open_line, int error_line) {
    return ErrorAt(error_line, absl::StrCat("unbalanced braces: End Site block (line ", open_line,
                                            ") is not closed"));
  }

  // A finite number, or an error naming `what`.
  absl::Status ParseNumber(absl::string_view text, int line, absl::string_view what,
                           double* value) {
    if (!absl::SimpleAtod(text, value)) {
      return ErrorAt(line, absl::StrCat(what, " ", Quoted(text), " is not a number"));
    }
    if (!std::isfinite(*value)) {
      return ErrorAt(line, absl::StrCat(what, " ", Quoted(text), " is NaN or infinite"));
    }
    return absl::OkStatus();
  }

  // Called with OFFSET consumed; the three values must share its line.
  absl::Status ParseOffset(const Token& keyword, Eigen::Vector3d* offset) {
    const std::vector<Token> values = tokens_.RestOfLine();
    if (values.size() != 3) {
      return ErrorAt(keyword.line,
                     absl::StrCat("OFFSET needs 3 values on its line, found ", values.size()));
    }
    for (int axis = 0; axis < 3; ++axis) {
      if (absl::Status status =
              ParseNumber(values[axis].text, keyword.line, "OFFSET value", &(*offset)[axis]);
          !status.ok()) {
        return status;
      }
    }
    return absl::OkStatus();
  }

  // Called with CHANNELS consumed; the count and names must share its line.
  absl::Status ParseChannels(const Token& keyword, int joint) {
    const std::vector<Token> rest = tokens_.RestOfLine();
    if (rest.empty()) return ErrorAt(keyword.line, "CHANNELS without a count");
    int declared = 0;
    if (!absl::SimpleAtoi(rest[0].text, &declared) || declared < 0 ||
        declared > kMaxChannelsPerJoint) {
      return ErrorAt(keyword.line,
                     absl::StrCat("CHANNELS count ", Quoted(rest[0].text),
                                  " is not an integer from 0 to ", kMaxChannelsPerJoint));
    }
    const int listed = static_cast<int>(rest.size()) - 1;
    if (listed != declared) {
      return ErrorAt(keyword.line, absl::StrCat("CHANNELS count mismatch: declares ", declared,
                                                " channels but lists ", listed));
    }
    BvhJoint& target = clip_.joints[joint];
    JointChannels& columns = channels_[joint];
    // Columns follow the order CHANNELS lines appear in the file.
    columns.first_value = values_per_frame_;
    for (int i = 1; i <= listed; ++i) {
      const ChannelName* match = nullptr;
      for (const ChannelName& candidate : kChannelNames) {
        if (absl::EqualsIgnoreCase(rest[i].text, candidate.name)) match = &candidate;
      }
      if (match == nullptr) {
        return ErrorAt(keyword.line, absl::StrCat("unknown channel name ", Quoted(rest[i].text)));
      }
      for (ChannelKind seen : columns.kinds) {
        if (seen == match->kind) {
          return ErrorAt(keyword.line, absl::StrCat("channel ", match->name, " listed twice"));
        }
      }
      columns.kinds.push_back(match->kind);
      target.channels.push_back(match->name);
    }
    values_per_frame_ += listed;
    return absl::OkStatus();
  }

  absl::Status ParseMotion() {
    absl::string_view line;
    absl::string_view value_text;

    if (!lines_.NextNonBlank(&line)) return ErrorAt(EndLine(), "missing 'Frames:' after MOTION");
    if (!MatchHeader(line, {"Frames"}, &value_text)) {
      return ErrorAt(lines_.line_number(), absl::StrCat("missing 'Frames:', found ",
                                                        Quoted(absl::StripAsciiWhitespace(line))));
    }
    int64_t frames = 0;
    if (!absl::SimpleAtoi(value_text, &frames)) {
      return ErrorAt(lines_.line_number(),
                     absl::StrCat("Frames: value ", Quoted(value_text), " is not an integer"));
    }
    if (frames < 0) {
      return ErrorAt(lines_.line_number(), absl::StrCat("negative Frames: ", frames));
    }
    if (frames > INT_MAX) {
      return ErrorAt(lines_.line_number(), absl::StrCat("Frames: ", frames, " is too large"));
    }
    clip_.num_frames = static_cast<int>(frames);

    if (!lines_.NextNonBlank(&line)) return ErrorAt(EndLine(), "missing 'Frame Time:'");
    if (!MatchHeader(line, {"Frame", "Time"}, &value_text)) {
      return ErrorAt(lines_.line_number(), absl::StrCat("missing 'Frame Time:', found ",
                                                        Quoted(absl::StripAsciiWhitespace(line))));
    }
    if (absl::Status status =
            ParseNumber(value_text, lines_.line_number(), "Frame Time:", &clip_.frame_time);
        !status.ok()) {
      return status;
    }
    if (clip_.frame_time <= 0) {
      return ErrorAt(lines_.line_number(),
                     absl::StrCat("Frame Time: must be positive, got ", value_text));
    }

    // Frame lines are skipped as blank, so a clip without channels would have no data lines.
    if (values_per_frame_ == 0 && clip_.num_frames > 0) {
      return ErrorAt(lines_.line_number(), "the hierarchy declares no channels");
    }

    const size_t num_joints = clip_.joints.size();
    std::vector<absl::string_view> tokens;
    std::vector<double> values(values_per_frame_);
    for (int frame = 0; frame < clip_.num_frames; ++frame) {
      if (!lines_.NextNonBlank(&line)) {
        return ErrorAt(EndLine(), absl::StrFormat("truncated file: frame index %d is missing, "
                                                  "file ends after %d of %d frames (Frames:)",
                                                  frame, frame, clip_.num_frames));
      }
      SplitTokens(line, &tokens);
      if (tokens.size() != static_cast<size_t>(values_per_frame_)) {
        return ErrorAt(lines_.line_number(),
                       absl::StrFormat("frame index %d has %s values, expected %d", frame,
                                       tokens.size() < static_cast<size_t>(values_per_frame_)
                                           ? absl::StrCat("too few (", tokens.size(), ")")
                                           : absl::StrCat("too many (", tokens.size(), ")"),
                                       values_per_frame_));
      }
      for (int i = 0; i < values_per_frame_; ++i) {
        // The hot loop: the label is only formatted once a value is known to be bad.
        if (!absl::SimpleAtod(tokens[i], &values[i]) || !std::isfinite(values[i])) {
          return ParseNumber(tokens[i], lines_.line_number(),
                             absl::StrFormat("frame index %d, value %d:", frame, i), &values[i]);
        }
      }
      clip_.root_translation.push_back(RootTranslation(values));
      for (size_t joint = 0; joint < num_joints; ++joint) {
        clip_.local_rotation.push_back(LocalRotation(values, channels_[joint]));
      }
    }

    if (lines_.NextNonBlank(&line)) {
      return ErrorAt(lines_.line_number(),
                     absl::StrCat("more frame lines than Frames: ", clip_.num_frames));
    }
    return absl::OkStatus();
  }

  Eigen::Vector3d RootTranslation(const std::vector<double>& values) const {
    Eigen::Vector3d translation = clip_.joints[0].offset;
    const JointChannels& root = channels_[0];
    for (size_t c = 0; c < root.kinds.size(); ++c) {
      if (IsPosition(root.kinds[c])) {
        translation[AxisOf(root.kinds[c])] = values[root.first_value + c];
      }
    }
    return translation;
  }

  static Eigen::Quaterniond LocalRotation(const std::vector<double>& values,
                                          const JointChannels& joint) {
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    for (size_t c = 0; c < joint.kinds.size(); ++c) {
      if (IsPosition(joint.kinds[c])) continue;  // non-root translations are ignored
      const double radians = values[joint.first_value + c] * kDegreesToRadians;
      rotation *= Eigen::Quaterniond(
          Eigen::AngleAxisd(radians, Eigen::Vector3d::Unit(AxisOf(joint.kinds[c]))));
    }
    return rotation.normalized();
  }

  std::string file_name_;
  LineReader lines_;
  TokenReader tokens_;
  BvhClip clip_;
  std::vector<JointChannels> channels_;  // parallel to clip_.joints
  absl::flat_hash_map<std::string, int> line_by_name_;
  int values_per_frame_ = 0;
};

}  // namespace

int BvhClip::JointIndex(absl::string_view name) const {
  for (size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

absl::StatusOr<BvhClip> ParseBvh(absl::string_view text, absl::string_view file_name) {
  if (text.size() > static_cast<uint64_t>(kMaxBvhFileBytes)) {
    return absl::InvalidArgumentError(absl::StrFormat("%s: file too large (%d bytes, limit %d)",
                                                      file_name, text.size(), kMaxBvhFileBytes));
  }
  // Quaternions take several times the text's size; a huge clip must not abort the process.
  try {
    return BvhParser(text, file_name).Parse();
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(absl::StrCat(file_name, ": out of memory while parsing"));
  }
}

absl::StatusOr<BvhClip> ReadBvhFile(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a directory"));
  }
  // Check before reading so an oversized file costs no memory.
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (!error && size > static_cast<std::uintmax_t>(kMaxBvhFileBytes)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: file too large (%d bytes, limit %d)", path, size, kMaxBvhFileBytes));
  }
  std::ifstream stream(path, std::ios::binary);
  if (!stream) return absl::NotFoundError(absl::StrCat(path, ": cannot open"));
  std::string text;
  try {
    if (!error) text.reserve(size);
    // Read in chunks with a cap: the size above is unknown for pipes and may change meanwhile.
    std::vector<char> buffer(1 << 16);
    while (stream) {
      stream.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      text.append(buffer.data(), static_cast<size_t>(stream.gcount()));
      if (text.size() > static_cast<uint64_t>(kMaxBvhFileBytes)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s: file too large (limit %d bytes)", path, kMaxBvhFileBytes));
      }
    }
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(absl::StrCat(path, ": out of memory while reading"));
  }
  if (stream.bad()) return absl::DataLossError(absl::StrCat(path, ": read error"));
  return ParseBvh(text, path);
}

}  // namespace modskill
