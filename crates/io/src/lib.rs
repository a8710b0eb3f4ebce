//! raykit-io (placeholder).
