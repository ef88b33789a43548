//! Amanatides–Woo traversal (placeholder, being written).
