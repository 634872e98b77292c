//! Sky: Preetham sky radiance, sun direction and colour, SH sky light (L1 foundation).
