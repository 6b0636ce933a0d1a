#!/usr/bin/env bash
# Fetches CGAL's data set from Debian's libcgal-demo package into data/ (ignored by git, never committed):
# data/meshes/{armadillo,bunny00,refined_elephant,camel,cactus}.off (the paper's models and the benchmark's), more
# models the normal-estimation benchmark also runs on (CAD parts with sharp creases, a scan with holes, a figure of
# three components, ...), and data/deformation/cactus.{sel,def}; and PCL's sample scans, written by PCL (ASCII and
# binary_compressed, organised clouds with NaN points, packed colours, extra fields), from Debian's python3-pcl
# package into data/pcd/ (the PCD reader's tests compare them with Open3D's reader).
# Idempotent: does nothing when the files are there.
set -euo pipefail
cd "$(dirname "$0")/.."
models=(armadillo bunny00 refined_elephant camel cactus fandisk anchor_dense turbine mech-holes-shark lion-head
        ChineseDragon-10kv elephant-with-holes blobby_3cc)
want=(data/deformation/cactus.sel data/deformation/cactus.def)
for m in "${models[@]}"; do want+=("data/meshes/$m.off"); done
pcl_scans=(official/IO/test_pcd official/Surface/bun0 pcldata/tutorials/correspondence_grouping/milk
           pcldata/tutorials/correspondence_grouping/milk_cartoon_all_small_clorox pcldata/tutorials/table_scene_lms400
           pcldata/tutorials/table_scene_mug_stereo_textured)
for s in "${pcl_scans[@]}"; do want+=("data/pcd/$(basename "$s").pcd"); done
missing=0
for f in "${want[@]}"; do [ -f "$f" ] || missing=1; done
[ $missing -eq 0 ] && exit 0

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ "$(id -u)" -eq 0 ]; then apt-get update -qq >/dev/null 2>&1 || true; fi
(cd "$work" && apt-get download libcgal-demo >/dev/null 2>&1) || {
  echo "fetch_data.sh: 'apt-get download libcgal-demo' failed (run apt-get update as root, check the network)" >&2; exit 1; }
dpkg-deb -x "$work"/libcgal-demo_*.deb "$work/deb"
doc="$work/deb/usr/share/doc/libcgal-dev"
mkdir -p data/meshes data/deformation
for m in "${models[@]}"; do
  tar -xzf "$doc/data.tar.gz" -C "$work" "data/meshes/$m.off"
  mv "$work/data/meshes/$m.off" data/meshes/
done
tar -xzf "$doc/examples.tar.gz" -C "$work" examples/Surface_mesh_deformation/data/cactus.sel \
  examples/Surface_mesh_deformation/data/cactus.def
mv "$work"/examples/Surface_mesh_deformation/data/cactus.{sel,def} data/deformation/
(cd "$work" && apt-get download python3-pcl >/dev/null 2>&1) || {
  echo "fetch_data.sh: 'apt-get download python3-pcl' failed (run apt-get update as root, check the network)" >&2; exit 1; }
dpkg-deb -x "$work"/python3-pcl_*.deb "$work/pcl"
mkdir -p data/pcd
for s in "${pcl_scans[@]}"; do cp "$work/pcl/usr/share/doc/python3-pcl/examples/$s.pcd" data/pcd/; done
echo "fetch_data.sh: models in data/meshes, cactus selection in data/deformation, PCL's scans in data/pcd" >&2
