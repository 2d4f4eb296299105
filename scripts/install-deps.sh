#!/usr/bin/env bash
# Installs the Debian 12 packages the project needs (build, tests, post-processing).
# Idempotent: packages already present are skipped by apt-get.
set -euo pipefail
PKGS=(build-essential cmake pkg-config
      libeigen3-dev libopenmpi-dev openmpi-bin libhdf5-dev
      libsundials-dev catch2 libtomlplusplus-dev libcli11-dev libfmt-dev
      libisal-dev         # ISA-L: the results file's chunk compression (20 times zlib's speed, same format), CRC-32
      libboost-dev        # Boost.Math headers: Clopper-Pearson intervals, binomial CDF (src/sampling/stopping.cpp)
      python3-numpy python3-h5py python3-matplotlib python3-scipy python3-pandas
      python3-ujson       # the report's runs.csv: shortest round-trip number formatting in C
      python3-venv        # the truss-report package installed into a venv (test postproc_install)
      weasyprint          # the report's PDF for signature (postproc/report.py writes report.pdf)
      poppler-utils       # pdftotext: the tests read the PDF's document block (postproc_verdicts)
      python3-mypy        # type check of the report's reading and judging layers (postproc_mypy)
      python3-xarray python3-h5netcdf  # xarray opens the campaign file with named dimensions (mpi_layout)
      help2man            # man pages from --help (cmake --install)
      python3-openturns   # independent cross-check of the Sobol' indices and sample marginals (tests); examples/openturns_form.py
      pybind11-dev python3-pybind11 python3-dev python3-pytest  # the Python module truss_deploy (python/) and its tests
      libsimbody-dev      # the cross-check against a general multibody engine (validation/simbody, docs/validation.md)
      clang libclang-rt-14-dev)  # the sanitizer and fuzzing stage (scripts/sanitize.sh)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  echo "[deps] apt-get update, then installing ${#missing[@]} packages: ${missing[*]}"
  $SUDO apt-get update -qq
  # -q: one line per package downloaded, unpacked and set up (progress without the bars).
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
  echo "[deps] done"
fi
