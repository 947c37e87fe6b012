// What the command-line tools share: "--key value" options checked against a
// known list, and the exit-status convention (0 ok, 2 bad input with one line
// naming what was wrong, 1 internal error).
#pragma once

#include <cstdint>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/measurement_csv.h"

namespace pc_ekf {

class CommandLine {
 public:
  CommandLine(std::string program, std::string usage)
      : program_(std::move(program)), usage_(std::move(usage)) {}

  // Returns -1 when parsed; otherwise the exit status (0 after --help, 2 on error).
  // `flags` take no value (has() tells whether given).
  int parse(int argc, char** argv, const std::vector<std::string>& known,
            const std::vector<std::string>& flags = {}) {
    for (int i = 1; i < argc; ++i) {
      const std::string key = argv[i];
      if (key == "-h" || key == "--help") {
        std::cout << usage_;
        return 0;
      }
      bool flag = false;
      for (const auto& f : flags) flag = flag || key == f;
      if (flag) {
        values_[key] = "";
        continue;
      }
      bool ok = false;
      for (const auto& k : known) ok = ok || key == k;
      if (!ok) return badInput("unknown option '" + key + "'\n" + usage_);
      if (i + 1 >= argc) return badInput("option " + key + " needs a value");
      values_[key] = argv[++i];
    }
    return -1;
  }

  bool has(const std::string& key) const { return values_.count(key) > 0; }
  const std::string& operator[](const std::string& key) const { return values_.at(key); }

  // Parses --seed style values; false (after reporting) when not a non-negative integer.
  bool unsignedValue(const std::string& key, std::uint64_t* value, int* status) const {
    const std::string& s = values_.at(key);
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 19) {
      *status = badInput(key + " '" + s + "' is not a non-negative integer");
      return false;
    }
    *value = std::stoull(s);
    return true;
  }

  int badInput(const std::string& reason) const {
    std::cerr << program_ << ": " << reason << "\n";
    return 2;
  }

  // Runs the tool's body, mapping the library's input errors to exit 2.
  template <class Body>
  int run(Body body) const {
    try {
      return body();
    } catch (const ConfigError& e) {
      return badInput(e.what());
    } catch (const CsvError& e) {
      return badInput(e.what());
    } catch (const BagError& e) {
      return badInput(e.what());
    } catch (const std::invalid_argument& e) {
      return badInput(e.what());
    } catch (const std::exception& e) {
      std::cerr << program_ << ": error: " << e.what() << "\n";
      return 1;
    }
  }

 private:
  std::string program_, usage_;
  std::map<std::string, std::string> values_;
};

}  // namespace pc_ekf
