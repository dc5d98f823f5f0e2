"""SeamlessGAN (paper sections 4-5): the networks, adversarial-expansion training, latent-space tiling
and the discriminator-guided crop search. Trains at the working resolution; knows nothing of USD.
"""
