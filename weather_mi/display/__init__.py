"""What turns renders into things to look at and numbers: the denoised display layer (``denoise``,
``denoise_features``), image metrics against the ground truth (``metrics``), MP4 movies (``movie``)
and animations of a time series (``animate``)."""
