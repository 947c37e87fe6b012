#include "pc_ekf/model/model_description.h"

#include <sstream>
#include <stdexcept>

namespace pc_ekf {

ModelDescription::ModelDescription(Parts parts) : p_(std::move(parts)) {
  for (const auto& c : p_.channels) channel_names_.push_back(c.name);
  for (const auto& c : p_.contacts) {
    contact_names_.push_back(c.name);
    road_columns_.push_back(c.road_column.empty() ? c.name : c.road_column);
  }
  const auto channel = [&](const std::string& n) {
    if (n.empty()) return -1;
    const int i = channelIndex(n);
    if (i < 0) throw std::invalid_argument(p_.name + ": joint channel '" + n + "' unknown");
    return i;
  };
  for (const auto& j : p_.joints) {
    suspensions_.push_back(
        {j.default_joint, j.config_key, channel(j.position_channel), channel(j.velocity_channel)});
  }
  for (const auto& c : p_.choices) {
    if (c.options.empty()) throw std::invalid_argument(p_.name + ": choice " + c.name + " empty");
  }
}

int ModelDescription::channelIndex(const std::string& name) const {
  for (std::size_t i = 0; i < channel_names_.size(); ++i) {
    if (channel_names_[i] == name) return static_cast<int>(i);
  }
  return -1;
}

std::vector<std::string> ModelDescription::defaultChannelNames() const {
  std::vector<std::string> names;
  for (const ChannelSpec& c : p_.channels) {
    if (c.selected_by_default) names.push_back(c.name);
  }
  return names;
}

int ModelDescription::choiceIndex(const std::string& name) const {
  for (std::size_t i = 0; i < p_.choices.size(); ++i) {
    if (p_.choices[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

ModelParameters ModelParameters::defaults(const ModelDescription& d) {
  ModelParameters p;
  p.values = d.parameters().defaults();
  p.settings = d.settings().defaults();
  for (const auto& c : d.choices()) p.choices.push_back(c.options.front());
  return p;
}

const std::string& ModelParameters::choice(const ModelDescription& d,
                                           const std::string& name) const {
  const int i = d.choiceIndex(name);
  if (i < 0 || static_cast<std::size_t>(i) >= choices.size()) {
    throw std::invalid_argument(d.name() + ": no choice '" + name + "'");
  }
  return choices[static_cast<std::size_t>(i)];
}

std::string ModelDescription::markdown() const {
  std::ostringstream o;
  o << "### `" << p_.name << "`\n\n" << p_.summary << "\n\n";
  o << "Parameters (the estimated vector, in this order):\n\n" << p_.parameters.markdown();
  if (p_.settings.size() > 0) {
    o << "\nSettings (fixed, not estimated):\n\n" << p_.settings.markdown();
  }
  if (!p_.choices.empty()) {
    o << "\n| choice | options (first: default) | description |\n|---|---|---|\n";
    for (const auto& c : p_.choices) {
      std::string opts;
      for (const auto& x : c.options) opts += (opts.empty() ? "" : " \\| ") + ("`" + x + "`");
      o << "| `" << c.name << "` | " << opts << " | " << c.description << " |\n";
    }
  }
  o << "\n| channel | unit | description |\n|---|---|---|\n";
  for (const auto& c : p_.channels) {
    o << "| `" << c.name << "` | " << c.unit << " | " << c.description << " |\n";
  }
  o << "\n| contact | road CSV column | description |\n|---|---|---|\n";
  for (std::size_t i = 0; i < p_.contacts.size(); ++i) {
    o << "| `" << p_.contacts[i].name << "` | `" << road_columns_[i] << "` | "
      << p_.contacts[i].description << " |\n";
  }
  o << "\n| joint (default name) | node.joints key | position | velocity |\n|---|---|---|---|\n";
  for (const auto& j : p_.joints) {
    o << "| `" << j.default_joint << "` | `" << j.config_key << "` | "
      << (j.position_channel.empty() ? "-" : "`" + j.position_channel + "`") << " | "
      << (j.velocity_channel.empty() ? "-" : "`" + j.velocity_channel + "`") << " |\n";
  }
  return o.str();
}

}  // namespace pc_ekf
