//! Proptest strategies (placeholder, being written).
