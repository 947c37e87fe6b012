// The re-open rule's own false alarms (docs/method.md §5.9). Under the model
// the windowed NIS still rises above its upper bound now and then, and
// `after` consecutive such samples re-open the filter: one or two times in
// 10 s of a correct model at 200 Hz. The re-open rate check expects these besides the
// load changes, so a healthy fast stream is not flagged for them.
#pragma once

namespace pc_ekf {

// Probability per sample that the rule re-opens a filter whose NIS is
// chi-square with `dof` degrees of freedom at every sample, independent
// between samples: the windowed mean over `window` samples (judged only when
// full) above the upper bound of the two-sided `confidence` interval for
// `after` consecutive samples, the window cleared after each re-open. Estimated once per
// argument set by a seeded simulation of the rule (cached; thread-safe).
double chanceReopenPerSample(int window, int dof, double confidence, int after);

// The simulation itself, uncached and without the table of the shipped
// rule (window 20, confidence 0.99, after 20, 1 to 24 dof), which holds its
// values so that no process spends its start-up on them; the test checks
// the table against it.
double simulateChanceReopenPerSample(int window, int dof, double confidence, int after);

}  // namespace pc_ekf
