#include "pc_ekf/ros/bag_check.h"

#include <rosbag/chunked_file.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <unordered_map>
#include <vector>

namespace pc_ekf {

namespace {

// Bag format 2.0 (http://wiki.ros.org/Bags/Format/2.0): after the version
// line, records <header_len u32><header><data_len u32><data>, a header being
// fields <len u32><name>=<value>; integers little endian.
constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr std::uint8_t kOpMessage = 0x02, kOpFileHeader = 0x03, kOpIndex = 0x04, kOpChunk = 0x05,
                       kOpChunkInfo = 0x06, kOpConnection = 0x07;
// No real header comes near these; they bound what a corrupt length makes us read.
constexpr std::uint64_t kMaxHeaderBytes = 1 << 20;
constexpr std::uint64_t kMaxConnectionBytes = 16 << 20;  // message definitions
// A compressed chunk's stated size is allocated before decompressing.
constexpr std::uint64_t kMinSizeCap = 64 << 20, kMaxRatio = 64;

using Fields = std::map<std::string, std::string>;

std::uint64_t little(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// Problems carry the byte offset; the first one ends the check.
struct Problem {
  std::string text;
};
[[noreturn]] void fail(std::uint64_t at, const std::string& what) {
  std::ostringstream o;
  o << "byte " << at << ": " << what;
  throw Problem{o.str()};
}

// ros::Header::parse without its out-of-bounds reads.
Fields parseFields(const std::uint8_t* p, std::uint64_t n, std::uint64_t at) {
  Fields fields;
  std::uint64_t i = 0;
  while (i < n) {
    if (n - i < 4) fail(at + i, "header field length cut off");
    const std::uint64_t len = little(p + i, 4);
    i += 4;
    if (len > n - i) {
      fail(at + i, "header field of " + std::to_string(len) + " bytes overruns its header");
    }
    const std::string field(reinterpret_cast<const char*>(p + i), len);
    const auto eq = field.find('=');
    if (eq == std::string::npos) fail(at + i, "header field without '='");
    fields[field.substr(0, eq)] = field.substr(eq + 1);
    i += len;
  }
  return fields;
}

std::uint64_t number(const Fields& f, const std::string& name, std::size_t bytes,
                     std::uint64_t at) {
  const auto it = f.find(name);
  if (it == f.end() || it->second.size() != bytes) {
    fail(at, "record header field '" + name + "' missing or not " + std::to_string(bytes) +
                 " bytes");
  }
  return little(reinterpret_cast<const std::uint8_t*>(it->second.data()), static_cast<int>(bytes));
}

struct Record {
  std::uint64_t pos = 0;  // of header_len
  std::uint8_t op = 0;
  Fields fields;
  std::uint64_t data_pos = 0, data_len = 0;
};

// Reads one record at `pos` of `bytes` (or of the file through `read`).
template <typename Read>
Record readRecord(std::uint64_t pos, std::uint64_t end, const Read& read) {
  Record r;
  r.pos = pos;
  std::uint8_t word[4];
  if (end - pos < 8) fail(pos, "record cut off (" + std::to_string(end - pos) + " bytes left)");
  read(pos, word, 4);
  const std::uint64_t header_len = little(word, 4);
  if (header_len > end - pos - 8 || header_len > kMaxHeaderBytes) {
    fail(pos, "record header length " + std::to_string(header_len) + " exceeds the " +
                  std::to_string(end - pos - 8) + " bytes left");
  }
  std::vector<std::uint8_t> header(header_len);
  read(pos + 4, header.data(), header_len);
  r.fields = parseFields(header.data(), header_len, pos + 4);
  r.op = static_cast<std::uint8_t>(number(r.fields, "op", 1, pos + 4));
  read(pos + 4 + header_len, word, 4);
  r.data_len = little(word, 4);
  r.data_pos = pos + 8 + header_len;
  if (r.data_len > end - r.data_pos) {
    fail(pos, "record data length " + std::to_string(r.data_len) + " exceeds the " +
                  std::to_string(end - r.data_pos) + " bytes left");
  }
  return r;
}

class BagFile {
 public:
  explicit BagFile(const std::string& path) : in_(path, std::ios::binary) {
    if (!in_) fail(0, "cannot open the file");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(in_.tellg());
  }
  std::uint64_t size() const { return size_; }
  void read(std::uint64_t pos, void* out, std::uint64_t n) {
    if (n == 0) return;
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(pos));
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    if (static_cast<std::uint64_t>(in_.gcount()) != n) fail(pos, "read error");
  }
  std::vector<std::uint8_t> data(const Record& r) {
    std::vector<std::uint8_t> d(r.data_len);
    read(r.data_pos, d.data(), r.data_len);
    return d;
  }

 private:
  std::ifstream in_;
  std::uint64_t size_ = 0;
};

// The chunk's records as rosbag sees them after decompressing; returns the
// offsets (within the uncompressed data) of its message records.
std::set<std::uint64_t> chunkMessageOffsets(BagFile& file, const Record& chunk) {
  const auto compression = chunk.fields.find("compression");
  if (compression == chunk.fields.end()) fail(chunk.pos, "chunk without 'compression'");
  const std::uint64_t size = number(chunk.fields, "size", 4, chunk.pos);
  std::vector<std::uint8_t> data = file.data(chunk);
  if (compression->second == "none") {
    if (size != chunk.data_len) {
      fail(chunk.pos, "uncompressed chunk states " + std::to_string(size) + " bytes but holds " +
                          std::to_string(chunk.data_len));
    }
  } else if (compression->second == "bz2" || compression->second == "lz4") {
    if (size > std::max(kMinSizeCap, kMaxRatio * chunk.data_len)) {
      fail(chunk.pos, "compressed chunk states an implausible size " + std::to_string(size));
    }
    std::vector<std::uint8_t> plain(size);
    try {
      rosbag::ChunkedFile().decompress(
          compression->second == "bz2" ? rosbag::compression::BZ2 : rosbag::compression::LZ4,
          plain.data(), static_cast<unsigned>(size), data.data(),
          static_cast<unsigned>(data.size()));
    } catch (const std::exception& e) {
      fail(chunk.pos, std::string("chunk does not decompress: ") + e.what());
    }
    data.swap(plain);
  } else {
    fail(chunk.pos, "unknown chunk compression '" + compression->second + "'");
  }
  std::set<std::uint64_t> messages;
  const auto read = [&data](std::uint64_t pos, void* out, std::uint64_t n) {
    if (n) std::memcpy(out, data.data() + pos, n);
  };
  for (std::uint64_t pos = 0; pos < data.size();) {
    Record r;
    try {
      r = readRecord(pos, data.size(), read);
    } catch (const Problem& p) {
      fail(chunk.data_pos, "in the chunk at " + std::to_string(chunk.pos) + ", " + p.text);
    }
    if (r.op == kOpMessage) messages.insert(pos);
    else if (r.op != kOpConnection) {
      fail(chunk.data_pos, "chunk at " + std::to_string(chunk.pos) + " holds a record of op " +
                               std::to_string(r.op) + " at its byte " + std::to_string(pos));
    }
    pos = r.data_pos + r.data_len;
  }
  return messages;
}

void checkBag(BagFile& file) {
  const std::uint64_t size = file.size();
  const std::uint64_t start = sizeof(kVersionLine) - 1;
  char version[sizeof(kVersionLine) - 1] = {};
  if (size < start) fail(0, "not a ROS bag (too short for the version line)");
  file.read(0, version, start);
  if (std::memcmp(version, kVersionLine, start) != 0) {
    fail(0, "not a ROS bag of format 2.0 (version line '#ROSBAG V2.0' expected)");
  }
  std::vector<Record> records;
  std::unordered_map<std::uint64_t, std::size_t> at;  // record position -> index
  const auto read = [&file](std::uint64_t pos, void* out, std::uint64_t n) {
    file.read(pos, out, n);
  };
  for (std::uint64_t pos = start; pos < size;) {
    records.push_back(readRecord(pos, size, read));
    at[pos] = records.size() - 1;
    pos = records.back().data_pos + records.back().data_len;
  }
  if (records.empty() || records[0].op != kOpFileHeader) fail(start, "no bag header record");
  const Record& header = records[0];
  if (header.fields.count("encryptor")) fail(header.pos, "encrypted bags are not supported");
  const std::uint64_t index_pos = number(header.fields, "index_pos", 8, header.pos);
  const std::uint64_t connections = number(header.fields, "conn_count", 4, header.pos);
  const std::uint64_t chunks = number(header.fields, "chunk_count", 4, header.pos);
  if (index_pos == 0) fail(header.pos, "the bag is not indexed (rosbag reindex repairs it)");
  const auto index = at.find(index_pos);
  if (index == at.end()) fail(header.pos, "index position " + std::to_string(index_pos) +
                                              " is not the start of a record");
  if (index->second + connections + chunks > records.size()) {
    fail(index_pos, "the index lists more connections and chunks than there are records");
  }

  std::set<std::uint64_t> connection_ids;
  for (std::uint64_t i = 0; i < connections; ++i) {
    const Record& c = records[index->second + i];
    if (c.op != kOpConnection) fail(c.pos, "connection record expected");
    connection_ids.insert(number(c.fields, "conn", 4, c.pos));
    if (c.data_len > kMaxConnectionBytes) fail(c.pos, "connection header too long");
    const std::vector<std::uint8_t> d = file.data(c);
    parseFields(d.data(), d.size(), c.data_pos);
  }

  std::map<std::uint64_t, std::set<std::uint64_t>> checked_chunks;  // chunk pos -> messages
  for (std::uint64_t i = 0; i < chunks; ++i) {
    const Record& info = records[index->second + connections + i];
    if (info.op != kOpChunkInfo) fail(info.pos, "chunk info record expected");
    if (number(info.fields, "ver", 4, info.pos) != 1) fail(info.pos, "chunk info version not 1");
    number(info.fields, "start_time", 8, info.pos);
    number(info.fields, "end_time", 8, info.pos);
    const std::uint64_t chunk_pos = number(info.fields, "chunk_pos", 8, info.pos);
    const std::uint64_t count = number(info.fields, "count", 4, info.pos);
    if (info.data_len != 8 * count) fail(info.pos, "chunk info data does not hold its count");
    const std::vector<std::uint8_t> pairs = file.data(info);
    std::set<std::uint64_t> chunk_connections;
    for (std::uint64_t k = 0; k < count; ++k) chunk_connections.insert(little(&pairs[8 * k], 4));

    const auto chunk = at.find(chunk_pos);
    if (chunk == at.end() || records[chunk->second].op != kOpChunk) {
      fail(info.pos, "chunk position " + std::to_string(chunk_pos) + " is not a chunk record");
    }
    auto messages = checked_chunks.find(chunk_pos);
    if (messages == checked_chunks.end()) {
      messages =
          checked_chunks.emplace(chunk_pos, chunkMessageOffsets(file, records[chunk->second])).first;
    }
    // rosbag reads one index record per connection of the chunk info, right after the chunk.
    if (chunk->second + chunk_connections.size() >= records.size()) {
      fail(chunk_pos, "index records after the chunk missing");
    }
    for (std::size_t k = 1; k <= chunk_connections.size(); ++k) {
      const Record& idx = records[chunk->second + k];
      if (idx.op != kOpIndex) fail(idx.pos, "index record expected after the chunk");
      if (number(idx.fields, "ver", 4, idx.pos) != 1) fail(idx.pos, "index version not 1");
      if (!connection_ids.count(number(idx.fields, "conn", 4, idx.pos))) {
        fail(idx.pos, "index record of a connection the bag does not define");
      }
      const std::uint64_t entries = number(idx.fields, "count", 4, idx.pos);
      if (idx.data_len != 12 * entries) fail(idx.pos, "index data does not hold its count");
      const std::vector<std::uint8_t> d = file.data(idx);
      for (std::uint64_t e = 0; e < entries; ++e) {
        if (!messages->second.count(little(&d[12 * e + 8], 4))) {
          fail(idx.data_pos + 12 * e, "index entry does not point at a message of its chunk");
        }
      }
    }
  }
}

// ---- serialized messages ----

struct FieldType {
  std::string base;     // "float64", "string", "std_msgs/Header", ...
  bool array = false;
  std::uint64_t fixed = 0;  // T[N]: N; T[]: 0
};
using Layout = std::map<std::string, std::vector<FieldType>>;  // type -> fields

int primitiveSize(const std::string& t) {
  static const std::map<std::string, int> sizes = {
      {"bool", 1},    {"int8", 1},    {"uint8", 1},   {"byte", 1},    {"char", 1},
      {"int16", 2},   {"uint16", 2},  {"int32", 4},   {"uint32", 4},  {"float32", 4},
      {"int64", 8},   {"uint64", 8},  {"float64", 8}, {"time", 8},    {"duration", 8}};
  const auto it = sizes.find(t);
  return it == sizes.end() ? 0 : it->second;
}

std::string package(const std::string& type) { return type.substr(0, type.find('/')); }

// gendeps text: the type's fields, then "=====" / "MSG: pkg/Type" sections.
Layout parseDefinition(const std::string& definition, const std::string& type) {
  Layout layout;
  std::string current = type;
  std::istringstream lines(definition);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("MSG: ", 0) == 0) {
      current = line.substr(5);
      while (!current.empty() && std::isspace(static_cast<unsigned char>(current.back()))) {
        current.pop_back();
      }
      layout[current];
      continue;
    }
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (line.find('=') != std::string::npos) continue;  // constant or section rule
    std::istringstream words(line);
    std::string t, name;
    if (!(words >> t >> name)) continue;
    FieldType f;
    const auto bracket = t.find('[');
    if (bracket != std::string::npos) {
      f.array = true;
      const std::string n = t.substr(bracket + 1, t.size() - bracket - 2);
      f.fixed = n.empty() ? 0 : std::stoull(n);
      t.erase(bracket);
    }
    if (t == "Header") t = "std_msgs/Header";
    if (!primitiveSize(t) && t != "string" && t.find('/') == std::string::npos) {
      t = package(current) + "/" + t;
    }
    f.base = t;
    layout[current].push_back(f);
  }
  return layout;
}

class MessageWalk {
 public:
  MessageWalk(const Layout& layout, const std::uint8_t* data, std::size_t size)
      : layout_(layout), data_(data), size_(size) {}

  void message(const std::string& type, int depth) {
    const auto it = layout_.find(type);
    if (it == layout_.end() || depth > 32) fail(pos_, "unknown field type " + type);
    for (const FieldType& f : it->second) {
      std::uint64_t count = 1;
      if (f.array) count = f.fixed ? f.fixed : u32();
      const std::uint64_t min = minSize(f.base, 0);
      if (count * std::max<std::uint64_t>(min, 1) > size_ - pos_) {
        fail(pos_, "a " + f.base + " array of " + std::to_string(count) +
                       " elements does not fit in the " + std::to_string(size_ - pos_) +
                       " bytes left");
      }
      const int p = primitiveSize(f.base);
      if (p) {
        pos_ += count * p;
        continue;
      }
      for (std::uint64_t k = 0; k < count; ++k) {
        if (f.base == "string") {
          const std::uint64_t len = u32();
          if (len > size_ - pos_) fail(pos_, "a string of " + std::to_string(len) + " bytes overruns");
          pos_ += len;
        } else {
          message(f.base, depth + 1);
        }
      }
    }
  }

 private:
  std::uint64_t u32() {
    if (size_ - pos_ < 4) fail(pos_, "length cut off");
    const std::uint64_t v = little(data_ + pos_, 4);
    pos_ += 4;
    return v;
  }
  std::uint64_t minSize(const std::string& type, int depth) const {
    if (const int p = primitiveSize(type)) return p;
    if (type == "string" || depth > 32) return 4;
    const auto it = layout_.find(type);
    if (it == layout_.end()) return 0;
    std::uint64_t s = 0;
    for (const FieldType& f : it->second) {
      s += f.array && !f.fixed ? 4 : (f.array ? f.fixed : 1) * minSize(f.base, depth + 1);
    }
    return s;
  }

  const Layout& layout_;
  const std::uint8_t* data_;
  std::uint64_t size_, pos_ = 0;
};

}  // namespace

std::string bagStructureProblem(const std::string& path) {
  try {
    BagFile file(path);
    checkBag(file);
  } catch (const Problem& p) {
    return p.text;
  } catch (const std::bad_alloc&) {
    return "out of memory while checking the bag";
  }
  return "";
}

std::string serializedMessageProblem(const std::string& definition, const std::string& type,
                                     const std::uint8_t* data, std::size_t size) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, std::string>, Layout> layouts;  // parsed once per type
  const Layout* layout = nullptr;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    auto it = layouts.find({definition, type});
    if (it == layouts.end()) {
      it = layouts.emplace(std::make_pair(definition, type), parseDefinition(definition, type)).first;
    }
    layout = &it->second;  // std::map nodes are stable
  }
  try {
    MessageWalk(*layout, data, size).message(type, 0);
  } catch (const Problem& p) {
    return p.text;
  }
  return "";
}

}  // namespace pc_ekf
