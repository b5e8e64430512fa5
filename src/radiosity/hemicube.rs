//! The hemicube (Cohen and Greenberg 1985): delta form factors and the item-buffer rasteriser.
