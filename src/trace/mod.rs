//! Pass two: a Whitted ray tracer (Whitted 1980) whose diffuse term is the radiosity solution.
