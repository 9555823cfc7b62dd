# syntax=docker/dockerfile:1
# The MoDD workbench image: the backend (modd-backend, FastAPI) serving the built
# frontend at /.
#
#   docker build -f docker/backend.Dockerfile -t modd-backend .
#
# WORKDIR /app = the repository root, as in a checkout (frontend/dist,
# .venv/bin/modd-backend).

ARG DEBIAN=bookworm
ARG PYTHON=3.11
ARG NODE=20
ARG UV=0.13.8

# -- the frontend (Vite) -------------------------------------------------------------
FROM node:${NODE}-${DEBIAN}-slim AS frontend
WORKDIR /src/frontend
COPY frontend/package.json frontend/package-lock.json ./
RUN npm ci --no-audit --no-fund --loglevel=error
COPY frontend ./
# The inspector forms import the metamodel's JSON Schema at build time (vite.config.ts).
COPY metamodel/modd.schema.json /src/metamodel/modd.schema.json
RUN npm run build

FROM ghcr.io/astral-sh/uv:${UV} AS uv

# -- the backend ------------------------------------------------------------------------
FROM python:${PYTHON}-slim-${DEBIAN} AS backend
COPY --from=uv /uv /usr/local/bin/uv
WORKDIR /app
ENV UV_LINK_MODE=copy UV_COMPILE_BYTECODE=1 UV_PYTHON_DOWNLOADS=never \
    UV_PROJECT_ENVIRONMENT=/app/.venv PATH=/app/.venv/bin:$PATH PYTHONUNBUFFERED=1

COPY pyproject.toml uv.lock ./
COPY metamodel/pyproject.toml metamodel/pyproject.toml
COPY generators/pyproject.toml generators/pyproject.toml
COPY runtime/python/pyproject.toml runtime/python/pyproject.toml
COPY backend/pyproject.toml backend/pyproject.toml
COPY launcher/pyproject.toml launcher/pyproject.toml
RUN uv sync --frozen --no-dev --no-install-workspace --package modd-backend
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
COPY backend backend
RUN uv sync --frozen --no-dev --package modd-backend
COPY --from=frontend /src/frontend/dist frontend/dist

EXPOSE 8080
CMD ["modd-backend", "--host", "0.0.0.0", "--port", "8080", "--data", "/var/lib/modd/backend"]
