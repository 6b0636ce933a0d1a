#!/usr/bin/env bash
# Fetches CGAL's data set from Debian's libcgal-demo package into data/ (ignored by git, never committed):
# data/meshes/{armadillo,bunny00,refined_elephant,camel,cactus}.off (the paper's models and the benchmark's), more
# models the normal-estimation benchmark also runs on (CAD parts with sharp creases, a scan with holes, a figure of
# three components, ...), and data/deformation/cactus.{sel,def}.
# Idempotent: does nothing when the files are there.
set -euo pipefail
cd "$(dirname "$0")/.."
models=(armadillo bunny00 refined_elephant camel cactus fandisk anchor_dense turbine mech-holes-shark lion-head
        ChineseDragon-10kv elephant-with-holes blobby_3cc)
want=(data/deformation/cactus.sel data/deformation/cactus.def)
for m in "${models[@]}"; do want+=("data/meshes/$m.off"); done
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
echo "fetch_data.sh: models in data/meshes, cactus selection in data/deformation" >&2
