"""Echo sources: the exact point-target oracle and ray-traced scenes."""
