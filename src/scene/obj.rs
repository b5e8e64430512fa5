//! OBJ/MTL loading through tobj: the only user of tobj.
