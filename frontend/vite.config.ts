/// <reference types="vitest/config" />
import { fileURLToPath } from "node:url";
import { defineConfig } from "vite";
import react from "@vitejs/plugin-react";

// The metamodel's JSON Schema is imported straight from metamodel/ through the
// `@schema` alias, so the inspector forms can never drift from the one source
// of truth (no copy step to keep in sync).
const metamodelDir = fileURLToPath(new URL("../metamodel", import.meta.url));

// During `npm run dev` the API is proxied to a backend on loopback
// (MODD_BACKEND, default http://127.0.0.1:8000).
const backend = process.env.MODD_BACKEND ?? "http://127.0.0.1:8000";

export default defineConfig({
  plugins: [react()],
  resolve: { alias: { "@schema": metamodelDir } },
  server: {
    host: "127.0.0.1",
    fs: { allow: [".", metamodelDir] },
    proxy: {
      "/api": { target: backend, changeOrigin: true, ws: true },
      "/scene": { target: backend, changeOrigin: true, ws: true },
    },
  },
  build: { outDir: "dist", chunkSizeWarningLimit: 2000 },
  test: {
    include: ["src/**/*.test.{ts,tsx}"],
    environment: "node",
  },
});
