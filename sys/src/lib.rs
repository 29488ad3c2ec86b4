//! Raw Embree bindings (generated at build time).
