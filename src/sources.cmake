# SPDX-License-Identifier: MIT
# The registration core: one pipeline stage per file (see docs/architecture.md).
set(KISSM_CORE_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/core/run_context.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/radix_sort.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/input.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/voxelize.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/neighbors.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/normals.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/ground.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/pair_features.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/fpfh.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/kdtree.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/descriptor_index.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/place_gate.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/matching.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/compat_graph.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/kcore.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/gnc_solver.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/yaw_solver.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/validity.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/point_index.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/refine.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/pipeline.cpp
  ${CMAKE_CURRENT_LIST_DIR}/core/features_codec.cpp
)
# The C boundary, by concern (src/capi/boundary.hpp: what every exported function shares).
set(KISSM_CAPI_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/capi/errors.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/config.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/points.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/result.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/matcher.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/features.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/ground.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/transform.cpp
  ${CMAKE_CURRENT_LIST_DIR}/capi/files.cpp
)
