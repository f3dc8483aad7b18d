"""The matcher benchmark: cases with known poses (real Stanford bunny scans, simulated scans with
exact truth; scan files of 5 and 20 million points), the stock Open3D pipeline it is measured against, and the runner
that times both in separate processes and writes docs/benchmarks.md (``python3 -m workcal_wb bench``)."""
