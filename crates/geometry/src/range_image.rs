//! Organized range images (placeholder, being written).
