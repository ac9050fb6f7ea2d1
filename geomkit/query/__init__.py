"""Distance queries: point projection, the voxel grid, surface distance, results."""
