# SPDX-License-Identifier: MIT
# Point file readers behind kissm_read_points().
set(KISSM_IO_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/read_points.cpp
  ${CMAKE_CURRENT_LIST_DIR}/file_bytes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/text_scan.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ply_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pcd_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/raw_bin_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/npy_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/xyz_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/las_reader.cpp
  ${CMAKE_CURRENT_LIST_DIR}/laz_records.cpp
)
