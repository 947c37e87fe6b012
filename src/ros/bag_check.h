// Checks a bag file before rosbag reads it, and a serialized message before
// roscpp deserializes it.
//
// rosbag 1.15 (Debian's librosbag_storage) trusts the lengths and offsets
// stored in the file: a corrupt length makes it allocate up to 4 GB
// (Bag::readHeader), read past its buffers (ros::Header::parse, and
// readMessageDataHeaderFromBuffer at an index offset), dereference a null
// connection (an index record naming an unknown connection) or abort on an
// assert (an uncompressed chunk whose two sizes differ). roscpp's
// deserializer resizes a vector to the length stored in the message before
// checking that the bytes are there (up to 32 GB for a float64[]). Found by
// fuzzing readBag (test/fuzz/fuzz_bag.cpp); these checks run first so a
// corrupt bag is refused with a message instead.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace pc_ekf {

// Walks every record of a format-2.0 bag (and every record inside each chunk,
// decompressing bz2/lz4 chunks) and checks what rosbag relies on: lengths
// fit, record headers parse, the file header's index position and counts
// lead to connection and chunk-info records, chunk infos point at chunks
// followed by their index records, index records name known connections and
// point at message records of their chunk, and an uncompressed chunk's sizes
// agree. "" when sound, else what is wrong and at which byte offset.
// Unindexed (index_pos 0), encrypted and format-1.2 bags are refused too.
std::string bagStructureProblem(const std::string& path);

// Checks that `size` bytes hold a message of the type `definition` describes
// (the full text of ros::message_traits::Definition<T>::value(), with its
// MSG: dependencies) as far as the deserializer needs: every string and
// array length fits in the bytes that remain. "" when fine.
std::string serializedMessageProblem(const std::string& definition, const std::string& type,
                                     const std::uint8_t* data, std::size_t size);

}  // namespace pc_ekf
