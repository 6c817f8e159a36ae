#!/usr/bin/env bash
# Installs the Debian 12 packages docunfold needs. Idempotent: does nothing
# when everything is present. As root it runs apt-get; otherwise it prints the
# exact command to run and exits 1.
#   scripts/install-deps.sh          check, install what is missing (root)
#   scripts/install-deps.sh --list   print the package list
set -euo pipefail

packages=(
  # toolchain (lld: a faster linker than GNU ld; Ninja: a no-op build in 0.1 s)
  build-essential cmake ninja-build pkg-config lld
  # images, features, freetype text rendering (synth), LSD, DeepFlow
  libopencv-dev libopencv-contrib-dev
  # the photo reader: libjpeg to tell a damaged JPEG from a whole one, EXIF
  # orientation and focal length, iPhones' HEIC photos
  libjpeg-dev libexif-dev libheif-dev
  # linear algebra everywhere
  libeigen3-dev
  # self-describing JSON files; command lines
  nlohmann-json3-dev libcli11-dev
  # .glb export of meshes
  libtinygltf-dev
  # k-d trees for nearest points (SfM points, footpoints)
  libnanoflann-dev
  # structure from motion; SQLite to read COLMAP's database (exact matching)
  colmap libsqlite3-dev
  # sparse Cholesky (CHOLMOD) for Gauss-Newton steps; L-BFGS as the
  # alternative solver. (CGAL, OpenMesh and Ceres are not needed: see the
  # README's dependency table for why.)
  libsuitesparse-dev liblbfgspp-dev
  # OCR for the CER/WER metrics and the PDF's text layer (Tesseract's own
  # renderers also write its ALTO and hOCR); qpdf sets the PDF's page size,
  # embeds the page image and joins pages into a book
  libtesseract-dev tesseract-ocr-eng libqpdf-dev qpdf
  # fonts for synth's pages
  fonts-dejavu-core fonts-dejavu-extra fonts-liberation2 fonts-freefont-ttf
  # JSON Schema validation of every file the pipeline reads or writes
  python3 python3-jsonschema
  # stage timing for the benchmark and the report (/usr/bin/time)
  time
  # scripts/code-size finds functions with universal-ctags (a test keeps
  # files and functions short)
  universal-ctags
  # tests (assimp reads our PLYs as an independent check; chromium opens the
  # HTML report; heif-enc, exiftool and jpegtran make phone-like photos;
  # poppler's pdfinfo, pdftotext and pdftoppm read our PDFs back, xmllint
  # checks the ALTO files against their schema)
  googletest libgtest-dev assimp-utils chromium libheif-examples libimage-exiftool-perl
  libjpeg-turbo-progs poppler-utils libxml2-utils
  # batches on a cluster (workflow/): Snakemake, and Slurm with munge for the
  # test that starts a single-node cluster
  snakemake slurm-wlm munge
  # fuzzing the file readers (pipeline.mk fuzz): clang and its libFuzzer,
  # ASan and UBSan runtimes
  clang libclang-rt-14-dev
)

if [[ "${1:-}" == "--list" ]]; then
  printf '%s\n' "${packages[@]}"
  exit 0
fi

# One dpkg-query for the whole list: one per package took 1.2 s, and
# pipeline.mk runs this script on every run.
declare -A installed=()
while read -r name status; do
  if [[ "$status" == "install ok installed" ]]; then installed[$name]=1; fi
done < <(dpkg-query -W -f='${Package} ${Status}\n' "${packages[@]}" 2>/dev/null || true)
missing=()
for p in "${packages[@]}"; do
  [[ -n "${installed[$p]:-}" ]] || missing+=("$p")
done
# Node.js and npm run the test tools (glTF validator, Playwright); any
# installation will do, Debian's packages when there is none.
command -v node >/dev/null && command -v npm >/dev/null || missing+=(nodejs npm)

# The npm test tools of tests/tools (pinned by its package-lock.json).
install_test_tools() {
  local tools
  tools="$(cd "$(dirname "$0")/.." && pwd)/tests/tools"
  if [[ ! -d "$tools/node_modules/gltf-validator" || ! -d "$tools/node_modules/playwright-core" ]]; then
    echo "docunfold: installing the npm test tools in tests/tools" >&2
    (cd "$tools" && npm ci --no-audit --no-fund --loglevel=error >&2)
  fi
}

if [[ ${#missing[@]} -eq 0 ]]; then
  install_test_tools
  exit 0
fi

cmd="apt-get install -y --no-install-recommends ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
  echo "docunfold: missing Debian packages; run as root:" >&2
  echo "  apt-get update && $cmd" >&2
  exit 1
fi
echo "docunfold: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
# A fresh machine may have no package lists yet.
if ! apt-get install -y --no-install-recommends "${missing[@]}" >/dev/null 2>&1; then
  apt-get update -qq
  apt-get install -y --no-install-recommends "${missing[@]}"
fi
install_test_tools
