#include "pc_ekf/io/measurement_csv.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <limits>
#include <sstream>

namespace pc_ekf {
namespace {

std::vector<std::string> splitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

[[noreturn]] void fail(const std::string& source, int line, const std::string& what) {
  throw CsvError(source + ": line " + std::to_string(line) + ": " + what);
}

// Parses one cell; empty or "nan" -> NaN when `missing_ok`.
double parseCell(const std::string& raw, bool missing_ok, const std::string& source, int line,
                 const std::string& column) {
  const std::string s = trim(raw);
  std::string lower = s;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (s.empty() || lower == "nan") {
    if (missing_ok) return std::numeric_limits<double>::quiet_NaN();
    fail(source, line, "column '" + column + "' is empty, expected a number");
  }
  // from_chars: the C locale's number, without a stream per cell (a long
  // record has millions); a leading '+' as a stream reads it.
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') ++first;
  double v = 0.0;
  const auto [end, error] = std::from_chars(first, last, v);
  if (error != std::errc() || end != last || !std::isfinite(v)) {
    fail(source, line, "column '" + column + "': '" + s + "' is not a finite number");
  }
  return v;
}

// Reads header + rows of numbers; the first column is time, strictly increasing.
// With `any_columns` the header is t and any distinct columns of `header`
// (after its first), in any order, and `header` is replaced by the file's
// before the first row. Each row goes to `take` as it is read: a long
// record is not held a second time as a table.
void readTable(std::istream& in, const std::string& source, std::vector<std::string>& header,
               bool missing_ok, bool any_columns,
               const std::function<void(const std::vector<double>&)>& take) {
  std::string line;
  int number = 0;
  std::string expected;
  for (const auto& h : header) expected += (expected.empty() ? "" : ",") + h;
  while (std::getline(in, line)) {
    ++number;
    if (!trim(line).empty()) break;
  }
  std::vector<std::string> got = splitCells(line);
  for (auto& g : got) g = trim(g);
  if (any_columns && !got.empty() && got[0] == header[0]) {
    for (std::size_t i = 1; i < got.size(); ++i) {
      const bool known = std::find(header.begin() + 1, header.end(), got[i]) != header.end();
      const bool repeated = std::find(got.begin() + 1, got.begin() + static_cast<long>(i),
                                      got[i]) != got.begin() + static_cast<long>(i);
      if (!known || repeated) {
        fail(source, number, "column '" + got[i] + "' " + (known ? "repeated" : "unknown") +
                                 ": expected t, then any of '" + expected.substr(2) + "'");
      }
    }
    if (got.size() < 2) fail(source, number, "no channel column after t");
    header = got;
    expected = trim(line);
  }
  if (got != header) fail(source, number, "header '" + trim(line) + "', expected '" + expected + "'");
  std::size_t rows = 0;
  double previous = 0.0;
  std::vector<double> row;
  while (std::getline(in, line)) {
    ++number;
    if (trim(line).empty()) continue;
    const auto cells = splitCells(line);
    if (cells.size() != header.size()) {
      fail(source, number, std::to_string(cells.size()) + " cells, expected " +
                               std::to_string(header.size()) + " (" + expected + ")");
    }
    row.assign(cells.size(), 0.0);
    row[0] = parseCell(cells[0], false, source, number, header[0]);
    for (std::size_t c = 1; c < cells.size(); ++c) {
      row[c] = parseCell(cells[c], missing_ok, source, number, header[c]);
    }
    if (rows > 0 && !(row[0] > previous)) {
      fail(source, number, "time " + trim(cells[0]) + " is not after the previous row's");
    }
    if (row[0] < 0.0) fail(source, number, "time " + trim(cells[0]) + " is negative");
    take(row);
    previous = row[0];
    ++rows;
  }
  if (rows == 0) fail(source, number, "no data rows after the header");
}

std::ifstream openOrThrow(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CsvError(path + ": cannot open the file");
  return in;
}

}  // namespace

namespace {

void readMeasurementRows(std::istream& in, const std::string& source,
                         const std::vector<std::string>& channels,
                         const std::function<void(Measurement&)>& take) {
  std::vector<std::string> header{"t"};
  header.insert(header.end(), channels.begin(), channels.end());
  // The file's columns in the model's channel order (the file's header is
  // read before the first row).
  std::vector<std::pair<int, int>> order;  // (model channel, file column)
  std::vector<double> values;
  readTable(in, source, header, true, true, [&](const std::vector<double>& row) {
    if (order.empty()) {
      for (std::size_t col = 1; col < header.size(); ++col) {
        const auto it = std::find(channels.begin(), channels.end(), header[col]);
        order.emplace_back(static_cast<int>(it - channels.begin()), static_cast<int>(col));
      }
      std::sort(order.begin(), order.end());
    }
    Measurement m;
    m.time = row[0];
    m.channels.reserve(order.size());
    values.clear();
    for (const auto& [c, col] : order) {
      if (std::isnan(row[static_cast<std::size_t>(col)])) continue;
      m.channels.push_back(c);
      values.push_back(row[static_cast<std::size_t>(col)]);
    }
    m.values = Eigen::Map<Eigen::VectorXd>(values.data(),
                                           static_cast<Eigen::Index>(values.size()));
    take(m);
  });
}

}  // namespace

MeasurementSeries readMeasurementCsv(std::istream& in, const std::string& source,
                                     const std::vector<std::string>& channels) {
  MeasurementSeries series;
  readMeasurementRows(in, source, channels, [&](Measurement& m) { series.push_back(std::move(m)); });
  return series;
}

MeasurementSeries readMeasurementCsvFile(const std::string& path,
                                         const std::vector<std::string>& channels) {
  std::ifstream in = openOrThrow(path);
  return readMeasurementCsv(in, path, channels);
}

void readMeasurementCsvFileRows(const std::string& path, const std::vector<std::string>& channels,
                                const std::function<void(Measurement&)>& take) {
  std::ifstream in = openOrThrow(path);
  readMeasurementRows(in, path, channels, take);
}

void writeMeasurementCsv(std::ostream& out, const MeasurementSeries& series,
                         const std::vector<std::string>& channels) {
  // The channels the series has (a model's IMU channels only when read).
  std::vector<bool> present(channels.size(), false);
  for (const auto& m : series) {
    for (int c : m.channels) {
      if (c >= 0 && c < static_cast<int>(present.size())) present[static_cast<std::size_t>(c)] = true;
    }
  }
  if (series.empty()) present.assign(channels.size(), true);
  out << "t";
  for (std::size_t c = 0; c < channels.size(); ++c) {
    if (present[c]) out << ',' << channels[c];
  }
  out << '\n' << std::setprecision(17);
  const int count = static_cast<int>(channels.size());
  for (const auto& m : series) {
    out << m.time;
    for (int c = 0; c < count; ++c) {
      if (!present[static_cast<std::size_t>(c)]) continue;
      out << ',';
      for (std::size_t i = 0; i < m.channels.size(); ++i) {
        if (m.channels[i] == c) out << m.values[i];
      }
    }
    out << '\n';
  }
}

ContactSeries readContactRoadCsv(std::istream& in, const std::string& source,
                                 const std::vector<std::string>& columns) {
  std::vector<std::string> header{"t"};
  header.insert(header.end(), columns.begin(), columns.end());
  ContactSeries road;
  road.heights.resize(columns.size());
  readTable(in, source, header, false, false, [&](const std::vector<double>& row) {
    road.t.push_back(row[0]);
    for (std::size_t c = 0; c < columns.size(); ++c) road.heights[c].push_back(row[c + 1]);
  });
  return road;
}

ContactSeries readContactRoadCsvFile(const std::string& path,
                                     const std::vector<std::string>& columns) {
  std::ifstream in = openOrThrow(path);
  return readContactRoadCsv(in, path, columns);
}

}  // namespace pc_ekf
