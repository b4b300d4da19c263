# SPDX-License-Identifier: MIT
"""The code of the benchmarks and studies of bench/: the scripts there (bench.py, map_bench.py, ...) are entry points
that call a module's ``main``; everything they share lives here, once.

* :mod:`.common`: paths, the machine's description, pinning, process memory, command lines, medians;
* :mod:`.geometry`: rotations and pose errors;
* :mod:`.data`: the real data (the pairs of ``../shared/data/index.tsv``, their kinds, voxel sizes and success
  thresholds, reading the clouds, the KITTI 07 keyframes' chain);
* :mod:`.scenes`: seeded synthetic outdoor scenes;
* :mod:`.reference`: the reference KISS-Matcher, called the same way by every benchmark;
* :mod:`.results`: saving results (the full raw JSON, or the reduced gzip file a page is rendered from) and
  reading them back;
* one module per benchmark or study (:mod:`.benchmark` with :mod:`.workers` and :mod:`.methods`,
  :mod:`.scan_to_map`, :mod:`.ground`, :mod:`.batch`, :mod:`.batch_accounting`, :mod:`.frame_study`,
  :mod:`.validity_study`, :mod:`.refine_sweep`), and in :mod:`.reports` one module per generated page.

The package and the modules bench.py's worker processes load (common, geometry, data, scenes, reference, results,
workers, methods, benchmark, reports) import numpy and the registration libraries only inside functions: a worker
imports them before it pins itself to its CPUs, and a thread pool started before that would not be pinned.
"""
