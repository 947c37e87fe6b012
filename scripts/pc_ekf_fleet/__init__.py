"""estimate_fleet's modules (docs/fleet.md): a fleet's bags estimated on Dask.

  inputs      the bags, the vehicle files, the per-vehicle configs and their
              identity (estimate_offline --config-hash)
  journal     results.jsonl: rows appended as they finish, the final table,
              results.csv
  scheduling  which bags to run (resume), the Dask run
  worker      the task a Dask worker runs: estimate_offline on one bag
  report      report.md, the figures, the progress bar
  cli         the command line (scripts/estimate_fleet)

Dask (python3-distributed) is imported only when bags are to be run.
"""
