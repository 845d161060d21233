// image_metrics: PSNR, SSIM, MS-SSIM, FLIP (in progress)
