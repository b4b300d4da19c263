# SPDX-License-Identifier: MIT
"""One module per generated page of docs/reports/, each with ``reduce`` (the fields of a run's results the page
is rendered from: what bench/results/ keeps) and the renderer, which reduces what it is given first, so that a
run's page and the page rewritten from its saved results are the same:

* :mod:`.benchmarks`: benchmarks.md and its plots (bench.py), the refinement section included;
* :mod:`.scan_to_map`: scan_to_map.md (map_bench.py);
* :mod:`.ground`: ground.md (ground_bench.py);
* :mod:`.batch`: batch-throughput*.md (batch_bench.py);
* :mod:`.common`: what the benchmark page's sections share (labels, colours, the results' index, formatting).
"""
