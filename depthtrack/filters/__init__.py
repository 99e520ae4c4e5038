"""Bayes filters: particle filter (low-variance resampling, MAP and k-means estimates), unscented and
linear Kalman filters, and circular-angle helpers."""
from .angles import angle_diff, circular_mean, wrap
from .kalman import KalmanFilter, kf_predict, kf_update
from .particle import (ParticleFilter, effective_sample_size, gaussian_angle_log_likelihood, kmeans_estimate,
                       low_variance_resample, multinomial_resample, normalise_log_weights)
from .ukf import MerweScaledSigmaPoints, UnscentedKalmanFilter, unscented_transform

__all__ = ["KalmanFilter", "MerweScaledSigmaPoints", "ParticleFilter", "UnscentedKalmanFilter", "angle_diff",
           "circular_mean", "effective_sample_size", "gaussian_angle_log_likelihood", "kf_predict", "kf_update",
           "kmeans_estimate", "low_variance_resample", "multinomial_resample", "normalise_log_weights",
           "unscented_transform", "wrap"]
