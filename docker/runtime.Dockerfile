# syntax=docker/dockerfile:1
# The MoDD runtime image: the C++ PubBroker and the Python runtime (SubBroker,
# simulator, MAVLink bridge, `modd up`). docker-compose.yml runs it twice: as the
# simulated drone and as the base station's SubBroker.
#
#   docker build -f docker/runtime.Dockerfile -t modd-runtime .
#
# Layout inside the image mirrors the repository (WORKDIR /app = the repository
# root), so commands read as they do in a checkout: build/bin/modd-pubbroker,
# metamodel/examples/demo.modd, .venv/bin/modd-subbroker.

ARG DEBIAN=bookworm
ARG PYTHON=3.11
ARG UV=0.13.8

# -- the PubBroker (C++20, CMake) ---------------------------------------------------
FROM debian:${DEBIAN}-slim AS pubbroker
RUN apt-get update \
 && apt-get install -y --no-install-recommends cmake ninja-build g++ libssl-dev libzstd-dev \
      liblz4-dev nlohmann-json3-dev \
 && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY runtime/cpp runtime/cpp
# Only the daemon: the GoogleTest units run in `make test`, not in the image build.
RUN cmake -S runtime/cpp -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DMODD_TESTS=OFF -DMODD_BIN_DIR=/src/build/bin \
 && cmake --build build/cpp --target modd-pubbroker

FROM ghcr.io/astral-sh/uv:${UV} AS uv

# -- the runtime ----------------------------------------------------------------------
FROM python:${PYTHON}-slim-${DEBIAN} AS runtime
RUN apt-get update \
 && apt-get install -y --no-install-recommends libssl3 libzstd1 liblz4-1 \
 && rm -rf /var/lib/apt/lists/*
COPY --from=uv /uv /usr/local/bin/uv
WORKDIR /app
ENV UV_LINK_MODE=copy UV_COMPILE_BYTECODE=1 UV_PYTHON_DOWNLOADS=never \
    UV_PROJECT_ENVIRONMENT=/app/.venv PATH=/app/.venv/bin:$PATH PYTHONUNBUFFERED=1

# Dependencies first (a layer that survives source edits), then the workspace.
COPY pyproject.toml uv.lock ./
COPY metamodel/pyproject.toml metamodel/pyproject.toml
COPY generators/pyproject.toml generators/pyproject.toml
COPY runtime/python/pyproject.toml runtime/python/pyproject.toml
COPY backend/pyproject.toml backend/pyproject.toml
COPY launcher/pyproject.toml launcher/pyproject.toml
RUN uv sync --frozen --no-dev --no-install-workspace --package modd-launcher
COPY metamodel metamodel
COPY generators generators
# The C++ client sources the generators carry into generated projects (one home:
# runtime/cpp; modd_gen.cpp_client reads them, a wheel includes them).
COPY runtime/cpp/include/modd/client runtime/cpp/include/modd/client
COPY runtime/cpp/src/client runtime/cpp/src/client
COPY runtime/cpp/include/modd/ingress/wire.hpp runtime/cpp/include/modd/ingress/wire.hpp
COPY runtime/cpp/include/modd/ingress/wire.gen.hpp runtime/cpp/include/modd/ingress/wire.gen.hpp
COPY runtime/cpp/cmake/aarch64-linux-gnu.cmake runtime/cpp/cmake/aarch64-linux-gnu.cmake
COPY runtime/python runtime/python
# `modd up` is the launcher's (it depends on the runtime and the generators).
COPY launcher launcher
RUN uv sync --frozen --no-dev --package modd-launcher

# `modd up` finds the PubBroker at build/bin/ of the repository, as in a checkout.
COPY --from=pubbroker /src/build/bin/modd-pubbroker build/bin/modd-pubbroker
COPY docker/drone.py docker/subbroker.toml docker/credentials.py docker/

# No ENTRYPOINT: docker-compose.yml gives each service its command.
CMD ["modd", "--help"]
