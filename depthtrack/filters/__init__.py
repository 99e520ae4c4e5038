"""Bayes filters: particle filter (low-variance resampling, MAP and k-means estimates), the
Rao-Blackwellised particle filter on a cycle state, unscented and linear Kalman filters, the RTS
smoother, and circular-angle helpers."""
from .angles import angle_diff, circular_mean, wrap
from .kalman import KalmanFilter, kf_predict, kf_update
from .particle import (ParticleFilter, effective_sample_size, gaussian_angle_log_likelihood, kmeans_estimate,
                       low_variance_resample, multinomial_resample, normalise_log_weights)
from .rbpf import CycleRBPF
from .smoother import rts_smooth
from .ukf import MerweScaledSigmaPoints, UnscentedKalmanFilter, unscented_transform

__all__ = ["CycleRBPF", "KalmanFilter", "MerweScaledSigmaPoints", "ParticleFilter", "UnscentedKalmanFilter",
           "angle_diff", "circular_mean", "effective_sample_size", "gaussian_angle_log_likelihood", "kf_predict",
           "kf_update",
           "kmeans_estimate", "low_variance_resample", "multinomial_resample", "normalise_log_weights",
           "rts_smooth", "unscented_transform", "wrap"]
