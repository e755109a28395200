import { fileURLToPath } from "node:url";
import react from "@vitejs/plugin-react";
import { defineConfig } from "vitest/config";

// The config is loaded with `--config frontend/vite.config.ts` from the repository root,
// so the root is pinned to this folder explicitly.
const root = fileURLToPath(new URL(".", import.meta.url));
const backend = process.env.TOUCHLINE_BACKEND ?? "http://127.0.0.1:8000";

const proxy = {
  "/api": { target: backend, changeOrigin: true, ws: true },
};

export default defineConfig({
  root,
  base: "/",
  plugins: [react()],
  build: {
    outDir: "dist",
    emptyOutDir: true,
    sourcemap: true,
  },
  server: { host: "127.0.0.1", port: 5173, proxy },
  preview: { host: "127.0.0.1", port: 4173, proxy },
  test: {
    root,
    include: ["src/**/*.test.ts", "src/**/*.test.tsx"],
    environment: "node",
  },
});
