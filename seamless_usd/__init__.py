"""seamless-usd: make USD / MaterialX material textures seamlessly tileable with SeamlessGAN."""
from __future__ import annotations

__version__ = "0.1.0"
__all__ = ["__version__"]
