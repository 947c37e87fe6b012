// estimator_node checkpoints (docs/reliability.md "Checkpoints"), the node run as a child
// process: killed with SIGKILL mid-record and restarted, it resumes at its
// last checkpoint and, fed the samples after it, publishes the estimates of
// an uninterrupted run; SIGINT writes a checkpoint; a checkpoint from another
// configuration or a corrupt one stops the node with status 2.
#include <fcntl.h>
#include <signal.h>

#include <algorithm>
#include <iostream>

#include "estimator_test_support.h"
#include "pc_ekf/io/checkpoint.h"

namespace pc_ekf::test {
namespace {

constexpr std::size_t kSamples = 100;  // speed_bump.yaml's record at N = 100
constexpr std::size_t kKillAfter = 40;
constexpr int kEvery = 7;

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("pc_ekf_ckpt_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

// estimator_node in namespace `ns` as a child process (fork/exec, so that it
// can be killed), stdout and stderr to files.
class NodeProcess {
 public:
  NodeProcess(const std::string& ns, const std::vector<std::string>& params)
      : log_(tempPath(ns.substr(1))) {
    std::vector<std::string> args{executableBeside("estimator_node"), "__name:=estimator_node",
                                  "__ns:=" + ns};
    args.insert(args.end(), params.begin(), params.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const std::string out = log_ + ".out", err = log_ + ".err";
    pid_ = ::fork();
    if (pid_ == 0) {  // only async-signal-safe calls until exec
      const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(o, 1);
      ::dup2(e, 2);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
  }
  ~NodeProcess() {
    if (running()) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    std::filesystem::remove(log_ + ".out");
    std::filesystem::remove(log_ + ".err");
  }
  bool running() const { return pid_ > 0 && !status_; }
  void signal(int sig) { ::kill(pid_, sig); }
  // Exit status; -signal when killed; nullopt when still running after `timeout` s.
  std::optional<int> wait(double timeout) {
    waitUntil(
        [&] {
          int raw = 0;
          if (::waitpid(pid_, &raw, WNOHANG) == pid_) {
            status_ = WIFEXITED(raw) ? WEXITSTATUS(raw) : -WTERMSIG(raw);
          }
          return status_.has_value();
        },
        timeout);
    return status_;
  }
  std::string out() const { return readText(log_ + ".out"); }
  std::string err() const { return readText(log_ + ".err"); }

 private:
  std::string log_;
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// The node's input and output in namespace `ns`.
struct NodeTopics {
  NodeTopics(ros::NodeHandle& nh, const std::string& ns)
      : joints(nh.advertise<sensor_msgs::JointState>(ns + "/suspension/joint_states", 1000)),
        road(nh.advertise<RoadProfile>(ns + "/road/profile", 100000)),
        estimates(nh, ns + "/parameter_estimate") {}
  bool connected() const {
    return joints.getNumSubscribers() > 0 && road.getNumSubscribers() > 0 &&
           estimates.connected();
  }
  // The node's input connections gone (its output link may linger until a
  // node of the same name registers: the master then replaces it).
  bool inputDisconnected() const {
    return joints.getNumSubscribers() == 0 && road.getNumSubscribers() == 0;
  }
  // Samples [from, to) one at a time, each once the previous estimate is in.
  // With `with_road`, the road messages up to each sample's stamp go first,
  // starting at the stamp of sample `from` - 1: a resumed node has no road
  // buffer, the interval after its checkpointed sample needs the road from it.
  void feed(const Record& r, std::size_t from, std::size_t to, bool with_road = false) {
    const double road_from = from > 0 ? r.samples[from - 1].time : 0.0;
    std::size_t next_road = static_cast<std::size_t>(
        std::lower_bound(r.road.t.begin(), r.road.t.end(), road_from - 1e-12) - r.road.t.begin());
    for (std::size_t k = from; k < to; ++k) {
      for (; with_road && next_road < r.road.t.size() && r.road.t[next_road] <= r.samples[k].time;
           ++next_road) {
        road.publish(roadProfileMessage(stampAt(origin, r.road.t[next_road]),
                                        r.road.left[next_road], r.road.right[next_road]));
      }
      const std::size_t before = estimates.size();
      joints.publish(jointStateFromMeasurement(r.samples[k], stampAt(origin, r.samples[k].time)));
      ASSERT_TRUE(estimates.waitForCount(before + 1, 20.0)) << "no estimate for sample " << k + 1;
    }
  }
  const ros::Time origin{1000, 0};
  ros::Publisher joints, road;
  Collector<ParameterEstimate> estimates;
};

class EstimatorCheckpoint : public ::testing::Test {
 protected:
  void SetUp() override {
    config_ = loadConfigFile(configPath("speed_bump.yaml"));
    config_.sampling.samples = static_cast<int>(kSamples);
    record_ = syntheticRecord(config_, config_.truth.seed);
    ASSERT_EQ(record_.samples.size(), kSamples);
  }
  // The same configuration for every node of a test: it is what the hash covers.
  std::vector<std::string> params(const std::string& checkpoint, int every = kEvery,
                                  bool topic_road = false) const {
    std::vector<std::string> p{"_config_file:=" + configPath("speed_bump.yaml"),
                               "_sampling/samples:=" + std::to_string(kSamples),
                               "_node/publish_pdf:=false"};
    if (topic_road) p.push_back("_road/source:=topic");
    if (!checkpoint.empty()) {
      p.push_back("_checkpoint_file:=" + checkpoint);
      p.push_back("_checkpoint_every:=" + std::to_string(every));
    }
    return p;
  }

  // A node killed after kKillAfter samples and restarted from its checkpoint
  // publishes, for the samples after the checkpoint, what a node never
  // stopped publishes (to 1e-9 relative). Road from the config or, with
  // `topic_road`, from road/profile (re-sent from the checkpointed sample on).
  void killAndResume(const std::string& ns, bool topic_road);

  ros::NodeHandle nh_;
  EstimatorConfig config_;
  Record record_;
};

// |a - b| over every mean, stddev and coefficient, absolute and relative.
struct Difference {
  double absolute = 0.0, relative = 0.0;
  void add(const std::vector<double>& a, const std::vector<double>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double d = std::abs(a[i] - b[i]);
      absolute = std::max(absolute, d);
      if (d > 0) relative = std::max(relative, d / std::max(std::abs(a[i]), std::abs(b[i])));
    }
  }
};

void EstimatorCheckpoint::killAndResume(const std::string& ns, bool topic_road) {
  // Reference: one node, the whole record, never stopped.
  std::vector<ParameterEstimate> reference;
  {
    NodeProcess node(ns + "_reference", params("", kEvery, topic_road));
    NodeTopics topics(nh_, ns + "_reference");
    ASSERT_TRUE(waitUntil([&] { return topics.connected(); }, 20.0)) << node.err();
    topics.feed(record_, 0, kSamples, topic_road);
    reference = topics.estimates.messages();
    node.signal(SIGINT);
    EXPECT_EQ(node.wait(20.0), 0) << node.err();
  }
  ASSERT_EQ(reference.size(), kSamples);

  const std::string file = tempPath(ns.substr(1) + ".ckpt");
  std::filesystem::remove(file);
  NodeTopics topics(nh_, ns);
  {
    NodeProcess node(ns, params(file, kEvery, topic_road));
    ASSERT_TRUE(waitUntil([&] { return topics.connected(); }, 20.0)) << node.err();
    topics.feed(record_, 0, kKillAfter, topic_road);
    // Checkpoints are written on a background thread: the one of sample 35
    // lands shortly after that sample's estimate.
    const auto written = [&] {
      try {
        return readCheckpoint(file).full.samples == static_cast<int>(kKillAfter / kEvery * kEvery);
      } catch (const CheckpointError&) {
        return false;  // not there yet
      }
    };
    ASSERT_TRUE(waitUntil(written, 10.0)) << node.err();
    node.signal(SIGKILL);
    EXPECT_EQ(node.wait(10.0), -SIGKILL);
  }
  // The last multiple of kEvery before the kill; samples after it are lost.
  const Checkpoint saved = readCheckpoint(file);
  const std::size_t resume_at = kKillAfter / kEvery * kEvery;  // 35
  ASSERT_EQ(saved.full.samples, static_cast<int>(resume_at));
  EXPECT_EQ(saved.last_sample.sec, stampAt(topics.origin, record_.samples[resume_at - 1].time).sec);
  EXPECT_EQ(saved.decimated.samples, static_cast<int>(resume_at / 10));
  EXPECT_EQ(saved.batch_samples.size(), resume_at);
  EXPECT_EQ(saved.counters.at("samples_processed"), resume_at);
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));
  if (topic_road) {  // the road both filters still need: from the decimated one's t = 0.9 s
    ASSERT_FALSE(saved.road.t.empty());
    EXPECT_LE(saved.road.t.front(), saved.decimated.time);
    EXPECT_GT(saved.road.t.front(), saved.decimated.time - 0.0015);
    EXPECT_GE(saved.road.t.back(), saved.full.time);
  } else {
    EXPECT_TRUE(saved.road.t.empty());
  }

  // The dead node's connections must be gone before the new one's count.
  ASSERT_TRUE(waitUntil([&] { return topics.inputDisconnected(); }, 20.0));
  topics.estimates.clear();
  NodeProcess node(ns, params(file, kEvery, topic_road));
  ASSERT_TRUE(waitUntil([&] { return topics.connected(); }, 20.0)) << node.err();
  topics.feed(record_, resume_at, kSamples, topic_road);
  const auto resumed = topics.estimates.messages();
  ASSERT_EQ(resumed.size(), kSamples - resume_at);
  EXPECT_EQ(resumed.front().sample_index, resume_at + 1);

  Difference diff;
  for (const ParameterEstimate& m : resumed) {
    const ParameterEstimate& ref = reference.at(m.sample_index - 1);
    EXPECT_EQ(m.header.stamp, ref.header.stamp);
    EXPECT_EQ(m.time, ref.time);
    diff.add(m.mean, ref.mean);
    diff.add(m.stddev, ref.stddev);
    diff.add(m.coefficients, ref.coefficients);
    diff.add(m.coherence_disagreement, ref.coherence_disagreement);
  }
  std::cout << "resumed at sample " << resume_at << ": max |difference| to the uninterrupted run "
            << diff.absolute << " (relative " << diff.relative << ") over " << resumed.size()
            << " estimates" << std::endl;
  EXPECT_LE(diff.relative, 1e-9);
  EXPECT_EQ(resumed.back().sample_index, kSamples);
  EXPECT_TRUE(resumed.back().healthy);

  node.signal(SIGINT);
  EXPECT_EQ(node.wait(20.0), 0) << node.err();
  EXPECT_NE(node.out().find("resumed from " + file + " at sample 35, t = 1.05"), std::string::npos)
      << node.out();
  EXPECT_NE(node.out().find(topic_road ? "(topic road" : "(analytic road"), std::string::npos)
      << node.out();
  // The shutdown checkpoint holds the whole record.
  EXPECT_EQ(readCheckpoint(file).full.samples, static_cast<int>(kSamples));
  std::filesystem::remove(file);
}

TEST_F(EstimatorCheckpoint, KilledAndRestartedEqualsUninterruptedRun) {
  killAndResume("/ckpt_run", false);
}

TEST_F(EstimatorCheckpoint, KilledAndRestartedWithTopicRoadEqualsUninterruptedRun) {
  killAndResume("/ckpt_road", true);
}

TEST_F(EstimatorCheckpoint, ShutdownWritesAndAnotherConfigIsRefused) {
  const std::string file = tempPath("config.ckpt");
  std::filesystem::remove(file);
  {
    // Every 1000 samples: only the shutdown (SIGINT) writes.
    NodeProcess node("/ckpt_config", params(file, 1000));
    NodeTopics topics(nh_, "/ckpt_config");
    ASSERT_TRUE(waitUntil([&] { return topics.connected(); }, 20.0)) << node.err();
    topics.feed(record_, 0, 3);
    EXPECT_FALSE(std::filesystem::exists(file));
    node.signal(SIGINT);
    EXPECT_EQ(node.wait(20.0), 0) << node.err();
    EXPECT_NE(node.out().find("checkpoint " + file + " written at sample 3 (shutdown)"),
              std::string::npos)
        << node.out();
  }
  ASSERT_EQ(readCheckpoint(file).full.samples, 3);

  // p = 3 instead of 4: the saved state does not apply.
  std::vector<std::string> other = params(file);
  other.push_back("_pc/order:=3");
  NodeProcess changed("/ckpt_other", other);
  EXPECT_EQ(changed.wait(30.0), 2) << changed.err();
  const std::string err = changed.err();
  EXPECT_NE(err.find("FATAL"), std::string::npos) << err;
  EXPECT_NE(err.find("checkpoint " + file), std::string::npos) << err;
  EXPECT_NE(err.find("config hash"), std::string::npos) << err;
  EXPECT_NE(err.find("configuration changed"), std::string::npos) << err;
  EXPECT_EQ(readCheckpoint(file).full.samples, 3);  // left for the right configuration

  // Right hash, state that does not fit: refused naming the key.
  {
    std::string text = readText(file);
    const std::size_t at = text.find("coherence_disagreement = ");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, text.find('\n', at) - at, "coherence_disagreement = 3 0.1 0.2 0.3");
    std::ofstream(file) << text;
    NodeProcess misfit("/ckpt_config", params(file));
    EXPECT_EQ(misfit.wait(30.0), 2) << misfit.err();
    EXPECT_NE(misfit.err().find("key 'coherence_disagreement' has 3 values, this configuration "
                                "estimates 2 parameters"),
              std::string::npos)
        << misfit.err();
  }

  // A damaged file is refused too, naming it.
  std::ofstream(file) << "format = pc_ekf_checkpoint 1\nconfig_hash = 0x00";
  NodeProcess corrupt("/ckpt_config", params(file));
  EXPECT_EQ(corrupt.wait(30.0), 2) << corrupt.err();
  EXPECT_NE(corrupt.err().find("checkpoint " + file + ": no 'end' line"), std::string::npos)
      << corrupt.err();
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace pc_ekf::test

int main(int argc, char** argv) {
  return pc_ekf::test::runRostests(argc, argv, "estimator_checkpoint_tester");
}
