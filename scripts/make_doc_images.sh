#!/usr/bin/env bash
# Regenerates every picture of the manual (doc/images/*.png) with the program, from the demo's generated
# tentacle and CGAL's real scans, and the Python page's with the package (examples/python/workflow.py), and
# checks that each stays within 300 KiB.
# Usage: scripts/make_doc_images.sh   (builds point-detail and the Python package in Release first;
#        DOC_IMAGES_DIR=DIR writes them to DIR instead, as CI does to check that the script still runs)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/release_build.sh point-detail cgal_ext_python
bash scripts/fetch_data.sh
build=${BUILD_DIR:-build}
pd() { "$build/src/point-detail" -q "$@"; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
img=${DOC_IMAGES_DIR:-doc/images}
mkdir -p "$img"
meshes=data/meshes

# The demo's tentacle (40,000 samples of a bumpy tube): details, scaling, enhancement, editing, up-sampling.
pd demo -o "$work/demo"
size() { echo --width "$1" --height "$2"; }
pd render -i "$work/demo/details_quadric.ply" -o "$img/tentacle_quadric_details.png" --color-by detail_normal --view iso $(size 480 480)
pd render -i "$work/demo/scale_0.6.ply" -o "$img/tentacle_scale_0.6.png" --color-by displacement \
  --legend "displacement along the normal, model units" --view iso $(size 560 400)
pd render -i "$work/demo/enhance_3.0.ply" -o "$img/tentacle_enhance_3.0.png" --color-by displacement \
  --legend "displacement along the normal, model units" --view iso $(size 560 400)
pd render -i "$work/demo/tentacle.ply" -o "$img/tentacle_edit_before.png" --color-by none --view iso $(size 400 400)
for order in linear quadric cubic; do
  pd render -i "$work/demo/edit_$order.ply" -o "$img/tentacle_edit_$order.png" --color-by displacement \
    --legend "distance moved, model units" --view iso $(size 400 400)
done
pd render -i "$work/demo/edit_stretch_upsampled.ply" -o "$img/tentacle_stretch_upsampled.png" --color-by inserted $(size 400 400)

# CGAL's scans (Debian's libcgal-demo), with the meshes' vertex normals.
pd details -i "$meshes/bunny00.off" -o "$work/b.ply" --order quadric --lambda 0.8 --mu 1.6 \
  --png "$img/bunny00_quadric_details.png" $(size 520 520)
pd enhance -i "$meshes/armadillo.off" -o "$work/leg.ply" -s 3 --roi sphere:-34,-32,10,25 --order quadric \
  --png "$img/armadillo_enhance_leg.png" $(size 400 400)
pd edit -i "$meshes/armadillo.off" -o "$work/pulled.ply" --edit doc/edits/armadillo_pull_arm.json --upsample
pd render -i "$work/pulled.ply" -o "$img/armadillo_pull_arm_upsampled.png" --color-by inserted $(size 400 400)
pd curvature -i "$meshes/armadillo.off" -o "$work/c.ply" --png "$img/armadillo_curvature.png" $(size 420 500)
pd simplify -i "$meshes/armadillo.off" -o "$work/s.ply" --max-cluster-size 50 --png "$img/armadillo_ssps.png" --view back $(size 560 560)
pd render -i "$meshes/armadillo.off" -o "$img/armadillo_edit_before.png" --color-by none $(size 400 400)
pd edit -i "$meshes/armadillo.off" -o "$work/e.ply" --edit doc/edits/armadillo_raise_arm.json \
  --png "$img/armadillo_edit_arm.png" $(size 400 400)
for strength in euclidean geodesic; do
  pd edit -i "$meshes/armadillo.off" -o "$work/w.ply" --edit doc/edits/armadillo_raise_arm_wide.json --strength-distance "$strength" \
    --png "$img/armadillo_wide_$strength.png" $(size 800 800)
done

# doc/python.md: the package's workflow on bunny00 (details, the selection, the edited ear), with Debian's
# interpreter and the package of the same build.
PYTHONPATH="$build/python" /usr/bin/python3 examples/python/workflow.py --data data "$work/python" >/dev/null
for picture in details selection edit; do cp "$work/python/$picture.png" "$img/python_$picture.png"; done

too_large=0
for f in "$img"/*.png; do
  bytes=$(stat -c %s "$f")
  if [ "$bytes" -gt $((300 * 1024)) ]; then echo "make_doc_images.sh: $f is $((bytes / 1024)) KiB (> 300 KiB)" >&2; too_large=1; fi
done
[ "$too_large" = 0 ] || exit 1
echo "make_doc_images.sh: $(ls "$img"/*.png | wc -l) pictures in $img, each within 300 KiB"
