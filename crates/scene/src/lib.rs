//! raykit-scene (placeholder).
