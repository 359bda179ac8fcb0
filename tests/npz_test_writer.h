// Writes NumPy .npz archives for tests. AMASS files cannot be redistributed, so tests
// fabricate look-alikes: a zip (local headers, central directory, end record) of "name.npy"
// members, stored or deflated, with correct CRCs, which numpy.load accepts.
// Inside namespace modskill, `testing::` now names this namespace: spell GoogleTest's as
// `::testing::`.
#ifndef MODSKILL_TESTS_NPZ_TEST_WRITER_H_
#define MODSKILL_TESTS_NPZ_TEST_WRITER_H_

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace modskill::testing {

class NpzWriter {
 public:
  // Adds member "<name>.npy" of dtype <f4 holding `values` in row-major order.
  void AddF32(const std::string& name, const std::vector<int64_t>& shape,
              const std::vector<float>& values) {
    AddNumeric(name, "<f4", shape, values);
  }

  // Adds member "<name>.npy" of dtype <f8 holding `values` in row-major order.
  void AddF64(const std::string& name, const std::vector<int64_t>& shape,
              const std::vector<double>& values) {
    AddNumeric(name, "<f8", shape, values);
  }

  // Adds a 0-d '<U' array, the way NumPy stores a Python str such as AMASS 'gender'.
  // `utf8` must be valid UTF-8.
  void AddString(const std::string& name, const std::string& utf8) {
    const std::vector<uint32_t> code_points = DecodeUtf8(utf8);
    std::string data;
    for (uint32_t code_point : code_points) AppendLittleEndian(&data, code_point, 4);
    // NumPy gives '' the dtype <U1 (one NUL), never <U0.
    if (code_points.empty()) AppendLittleEndian(&data, 0, 4);
    const size_t length = code_points.empty() ? 1 : code_points.size();
    AddRawMember(name + ".npy",
                 MakeNpy("<U" + std::to_string(length), /*fortran_order=*/false, {}, data));
  }

  // Adds a member with arbitrary bytes, for unusual or deliberately broken members.
  // `member_name` is the full name inside the zip, e.g. "poses.npy".
  void AddRawMember(const std::string& member_name, std::string bytes) {
    members_.push_back({member_name, std::move(bytes)});
  }

  // Builds a format 1.0 .npy file: header dict padded (as NumPy does) so that the data starts
  // on a 64-byte boundary, then `data` verbatim.
  static std::string MakeNpy(const std::string& descr, bool fortran_order,
                             const std::vector<int64_t>& shape, const std::string& data) {
    std::string dict = "{'descr': '" + descr +
                       "', 'fortran_order': " + (fortran_order ? "True" : "False") +
                       ", 'shape': " + PythonShape(shape) + ", }";
    constexpr size_t kPreambleSize = 10;  // magic, version, 16-bit header length.
    const size_t unpadded = kPreambleSize + dict.size() + 1;
    const size_t padded = (unpadded + 63) / 64 * 64;
    dict.append(padded - unpadded, ' ');
    dict.push_back('\n');
    std::string npy("\x93NUMPY\x01\x00", 8);
    AppendLittleEndian(&npy, dict.size(), 2);
    return npy + dict + data;
  }

  // The archive's bytes. With `zip64_records`, every size and offset goes through the zip64
  // extra fields and a zip64 end record, as a writer does for archives over 4 GiB (NumPy
  // writes such local headers always); this exercises that path on a small archive.
  std::string Serialize(bool compress, bool zip64_records = false) const {
    std::string archive;
    std::string directory;
    for (const Member& member : members_) {
      const StoredMember stored = Store(member, compress, archive.size());
      AppendLocalEntry(member, stored, zip64_records, &archive);
      AppendCentralEntry(member, stored, zip64_records, &directory);
    }
    const uint64_t directory_offset = archive.size();
    archive += directory;
    AppendEndRecords(directory.size(), directory_offset, zip64_records, &archive);
    return archive;
  }

  // Returns false when the file cannot be written or an Add call had a shape that does not
  // match its values.
  bool Write(const std::string& path, bool compress) const {
    if (!consistent_) return false;
    const std::string archive = Serialize(compress);
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(archive.data(), static_cast<std::streamsize>(archive.size()));
    file.close();
    return !file.fail();
  }

 private:
  struct Member {
    std::string name;
    std::string bytes;
  };

  // A member as the archive holds it: its bytes after compression, and what the headers say.
  struct StoredMember {
    std::string data;
    uint32_t crc = 0;
    uint16_t method = 0;  // 0 stored, 8 deflated
    uint64_t header_offset = 0;
  };

  static StoredMember Store(const Member& member, bool compress, uint64_t header_offset) {
    StoredMember stored;
    stored.data = compress ? Deflate(member.bytes) : member.bytes;
    stored.crc =
        static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(member.bytes.data()),
                                    static_cast<uInt>(member.bytes.size())));
    stored.method = compress ? 8 : 0;
    stored.header_offset = header_offset;
    return stored;
  }

  // The local file header, its zip64 extra field if asked for, then the stored data.
  static void AppendLocalEntry(const Member& member, const StoredMember& stored,
                               bool zip64_records, std::string* archive) {
    std::string local_extra;
    if (zip64_records) {
      AppendLittleEndian(&local_extra, 1, 2);
      AppendLittleEndian(&local_extra, 16, 2);
      AppendLittleEndian(&local_extra, member.bytes.size(), 8);
      AppendLittleEndian(&local_extra, stored.data.size(), 8);
    }
    AppendLittleEndian(archive, 0x04034b50, 4);
    AppendLittleEndian(archive, zip64_records ? 45 : 20, 2);  // version needed
    AppendLittleEndian(archive, 0, 2);                        // flags
    AppendLittleEndian(archive, stored.method, 2);
    AppendLittleEndian(archive, 0, 2);       // time 00:00:00
    AppendLittleEndian(archive, 0x0021, 2);  // date 1980-01-01
    AppendLittleEndian(archive, stored.crc, 4);
    AppendLittleEndian(archive, zip64_records ? 0xFFFFFFFFu : stored.data.size(), 4);
    AppendLittleEndian(archive, zip64_records ? 0xFFFFFFFFu : member.bytes.size(), 4);
    AppendLittleEndian(archive, member.name.size(), 2);
    AppendLittleEndian(archive, local_extra.size(), 2);
    *archive += member.name;
    *archive += local_extra;
    *archive += stored.data;
  }

  // The member's central directory header, with its zip64 extra field if asked for.
  static void AppendCentralEntry(const Member& member, const StoredMember& stored,
                                 bool zip64_records, std::string* directory) {
    std::string central_extra;
    if (zip64_records) {
      AppendLittleEndian(&central_extra, 1, 2);
      AppendLittleEndian(&central_extra, 24, 2);
      AppendLittleEndian(&central_extra, member.bytes.size(), 8);
      AppendLittleEndian(&central_extra, stored.data.size(), 8);
      AppendLittleEndian(&central_extra, stored.header_offset, 8);
    }
    AppendLittleEndian(directory, 0x02014b50, 4);
    AppendLittleEndian(directory, zip64_records ? 45 : 20, 2);  // version made by
    AppendLittleEndian(directory, zip64_records ? 45 : 20, 2);  // version needed
    AppendLittleEndian(directory, 0, 2);                        // flags
    AppendLittleEndian(directory, stored.method, 2);
    AppendLittleEndian(directory, 0, 2);
    AppendLittleEndian(directory, 0x0021, 2);
    AppendLittleEndian(directory, stored.crc, 4);
    AppendLittleEndian(directory, zip64_records ? 0xFFFFFFFFu : stored.data.size(), 4);
    AppendLittleEndian(directory, zip64_records ? 0xFFFFFFFFu : member.bytes.size(), 4);
    AppendLittleEndian(directory, member.name.size(), 2);
    AppendLittleEndian(directory, central_extra.size(), 2);
    AppendLittleEndian(directory, 0, 2);  // comment length
    AppendLittleEndian(directory, 0, 2);  // disk number
    AppendLittleEndian(directory, 0, 2);  // internal attributes
    AppendLittleEndian(directory, 0, 4);  // external attributes
    AppendLittleEndian(directory, zip64_records ? 0xFFFFFFFFu : stored.header_offset, 4);
    *directory += member.name;
    *directory += central_extra;
  }

  // After the central directory: the zip64 end record and locator if asked for, then the end
  // of central directory record.
  void AppendEndRecords(uint64_t directory_size, uint64_t directory_offset, bool zip64_records,
                        std::string* archive) const {
    if (zip64_records) {
      const uint64_t zip64_end_offset = archive->size();
      AppendLittleEndian(archive, 0x06064b50, 4);
      AppendLittleEndian(archive, 44, 8);  // size of the rest of this record
      AppendLittleEndian(archive, 45, 2);
      AppendLittleEndian(archive, 45, 2);
      AppendLittleEndian(archive, 0, 4);  // this disk
      AppendLittleEndian(archive, 0, 4);  // disk with the central directory
      AppendLittleEndian(archive, members_.size(), 8);
      AppendLittleEndian(archive, members_.size(), 8);
      AppendLittleEndian(archive, directory_size, 8);
      AppendLittleEndian(archive, directory_offset, 8);

      AppendLittleEndian(archive, 0x07064b50, 4);
      AppendLittleEndian(archive, 0, 4);  // disk with the zip64 end record
      AppendLittleEndian(archive, zip64_end_offset, 8);
      AppendLittleEndian(archive, 1, 4);  // total disks
    }
    AppendLittleEndian(archive, 0x06054b50, 4);
    AppendLittleEndian(archive, 0, 2);  // this disk
    AppendLittleEndian(archive, 0, 2);  // disk with the central directory
    AppendLittleEndian(archive, zip64_records ? 0xFFFFu : members_.size(), 2);
    AppendLittleEndian(archive, zip64_records ? 0xFFFFu : members_.size(), 2);
    AppendLittleEndian(archive, zip64_records ? 0xFFFFFFFFu : directory_size, 4);
    AppendLittleEndian(archive, zip64_records ? 0xFFFFFFFFu : directory_offset, 4);
    AppendLittleEndian(archive, 0, 2);  // comment length
  }

  template <typename T>
  void AddNumeric(const std::string& name, const std::string& descr,
                  const std::vector<int64_t>& shape, const std::vector<T>& values) {
    int64_t count = 1;
    for (int64_t dimension : shape) count *= dimension;
    if (count != static_cast<int64_t>(values.size())) consistent_ = false;
    std::string data;
    for (T value : values) {
      // Serialise by value, not by memory layout, so the file is little-endian on any host.
      uint64_t bits = 0;
      std::memcpy(&bits, &value, sizeof(T));
      AppendLittleEndian(&data, bits, sizeof(T));
    }
    AddRawMember(name + ".npy", MakeNpy(descr, /*fortran_order=*/false, shape, data));
  }

  static void AppendLittleEndian(std::string* out, uint64_t value, int width) {
    for (int i = 0; i < width; ++i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
  }

  static std::string PythonShape(const std::vector<int64_t>& shape) {
    std::string text = "(";
    for (size_t i = 0; i < shape.size(); ++i) {
      if (i > 0) text += ", ";
      text += std::to_string(shape[i]);
    }
    if (shape.size() == 1) text += ",";
    return text + ")";
  }

  static std::vector<uint32_t> DecodeUtf8(const std::string& utf8) {
    std::vector<uint32_t> code_points;
    for (size_t i = 0; i < utf8.size();) {
      const unsigned char lead = static_cast<unsigned char>(utf8[i]);
      const int length = lead < 0x80 ? 1 : lead < 0xE0 ? 2 : lead < 0xF0 ? 3 : 4;
      uint32_t code_point = length == 1   ? lead
                            : length == 2 ? lead & 0x1F
                            : length == 3 ? lead & 0x0F
                                          : lead & 0x07;
      for (int k = 1; k < length && i + k < utf8.size(); ++k) {
        code_point = (code_point << 6) | (static_cast<unsigned char>(utf8[i + k]) & 0x3F);
      }
      code_points.push_back(code_point);
      i += length;
    }
    return code_points;
  }

  // Raw deflate (no zlib header), as zip stores it.
  static std::string Deflate(const std::string& raw) {
    z_stream stream{};
    deflateInit2(&stream, Z_DEFAULT_COMPRESSION, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
    std::string out(deflateBound(&stream, static_cast<uLong>(raw.size())), '\0');
    stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
    stream.avail_in = static_cast<uInt>(raw.size());
    stream.next_out = reinterpret_cast<Bytef*>(out.data());
    stream.avail_out = static_cast<uInt>(out.size());
    deflate(&stream, Z_FINISH);
    out.resize(stream.total_out);
    deflateEnd(&stream);
    return out;
  }

  std::vector<Member> members_;
  bool consistent_ = true;
};

}  // namespace modskill::testing

#endif  // MODSKILL_TESTS_NPZ_TEST_WRITER_H_
