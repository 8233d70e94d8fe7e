"""Self-contact of rods: segment distances, continuous collision detection, contact treatments."""
