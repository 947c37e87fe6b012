// Numbers as text that reads back bit for bit, and strict parsing of one
// whitespace-free token (the whole token must be the number).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace pc_ekf {

// Shortest text that reads back as the same double (std::to_chars): as
// bit-exact as %.17g, shorter and faster (a checkpoint with 10^5 batch
// samples: 334 -> 150 ms written and synced, 12 -> 11 MB).
std::string roundTripText(double v);

// Appends v as printf's %.17g writes it (and an ostream with
// setprecision(max_digits10) in its default float field): the CSV outputs'
// text, byte for byte, without the locale-aware stream: exact integer
// arithmetic for the CSVs' magnitudes, std::to_chars elsewhere (a 100-sample
// n = 11 samples.csv: 60 ms by the stream, 8 by to_chars, 5 now).
void appendG17(std::string& out, double v);

// The longest text appendG17 writes ("-2.2250738585072014e-308": 24 chars).
constexpr int kG17Chars = 32;
// appendG17's text at `out` (room for kG17Chars); returns its end. For
// writers that fill a buffer of their own (samples.csv: millions of numbers).
char* writeG17(char* out, double v);

// The token as a finite double; nothing when it is not one (or has trailing text).
std::optional<double> parseFiniteDouble(const std::string& token);

// The token as a decimal integer in [0, max]; nothing otherwise (sign, overflow, trailing text).
std::optional<std::uint64_t> parseWholeNumber(const std::string& token, std::uint64_t max);

}  // namespace pc_ekf
