//! Ray queries against the scene's triangles: the only user of obvhs.
