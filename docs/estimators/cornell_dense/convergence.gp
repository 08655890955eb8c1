# Written by `tpb converge`; re-plot with `gnuplot convergence.gp` in this folder
# (or tools/plot_convergence <folder>). Data: convergence.csv.
set datafile separator ','
set logscale xy
set format x '%g'
set format y '%g'
set xlabel 'CPU time per method, all threads (s)'
set ylabel 'relative RMSE against the reference'
set grid xtics ytics mxtics mytics lc rgb '#dddddd'
set key outside below
set title "cornell_dense.json, 32x32x32 bins, real time, delta emission" noenhanced
set terminal svg size 900,640 dynamic font 'Helvetica,13' background rgb 'white'
set output 'convergence.svg'
plot 'convergence.csv' using (strcol(1) eq 'beam2d' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#c0392b' title 'photon beams beam2d, transient volume (slope -0.24)', \
     'convergence.csv' using (strcol(1) eq 'beam2d' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#c0392b' title 'photon beams beam2d, steady image (slope -0.24)', \
     'convergence.csv' using (strcol(1) eq 'beam1d' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#27ae60' title 'photon beams beam1d, transient volume (slope -0.28)', \
     'convergence.csv' using (strcol(1) eq 'beam1d' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#27ae60' title 'photon beams beam1d, steady image (slope -0.28)', \
     'convergence.csv' using (strcol(1) eq 'point2d' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#8e44ad' title 'photon beams point2d, transient volume (slope -0.31)', \
     'convergence.csv' using (strcol(1) eq 'point2d' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#8e44ad' title 'photon beams point2d, steady image (slope -0.27)', \
     'convergence.csv' using (strcol(1) eq 'point3d' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#d68910' title 'photon beams point3d, transient volume (slope -0.36)', \
     'convergence.csv' using (strcol(1) eq 'point3d' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#d68910' title 'photon beams point3d, steady image (slope -0.29)', \
     'convergence.csv' using (strcol(1) eq 'beam2d+box' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#16a085' title 'photon beams beam2d+box, transient volume (slope -0.23)', \
     'convergence.csv' using (strcol(1) eq 'beam2d+box' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#16a085' title 'photon beams beam2d+box, steady image (slope -0.25)', \
     'convergence.csv' using (strcol(1) eq 'beam1d+box' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#7f8c8d' title 'photon beams beam1d+box, transient volume (slope -0.25)', \
     'convergence.csv' using (strcol(1) eq 'beam1d+box' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#7f8c8d' title 'photon beams beam1d+box, steady image (slope -0.25)', \
     'convergence.csv' using (strcol(1) eq 'point2d+box' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#e84393' title 'photon beams point2d+box, transient volume (slope -0.34)', \
     'convergence.csv' using (strcol(1) eq 'point2d+box' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#e84393' title 'photon beams point2d+box, steady image (slope -0.29)', \
     'convergence.csv' using (strcol(1) eq 'point3d+box' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#2c3e50' title 'photon beams point3d+box, transient volume (slope -0.36)', \
     'convergence.csv' using (strcol(1) eq 'point3d+box' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#2c3e50' title 'photon beams point3d+box, steady image (slope -0.30)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#2471a3' title 'path tracing, transient volume (slope -0.79)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#2471a3' title 'path tracing, steady image (slope -0.80)', \
     0.214923 with lines dt 3 lw 1.5 lc rgb '#555555' title 'own error of the reference (transient volume)', \
     0.0653754 with lines dt 4 lw 1 lc rgb '#999999' title 'own error of the reference (steady image)'
set terminal pngcairo size 900,640 font 'Helvetica,11' background rgb 'white'
set output 'convergence.png'
replot
set output
set ylabel 'relative mean absolute error against the reference'
set terminal svg size 900,640 dynamic font 'Helvetica,13' background rgb 'white'
set output 'convergence_l1.svg'
plot 'convergence.csv' using (strcol(1) eq 'beam2d' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#c0392b' title 'photon beams beam2d, transient volume (slope -0.25)', \
     'convergence.csv' using (strcol(1) eq 'beam2d' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#c0392b' title 'photon beams beam2d, steady image (slope -0.25)', \
     'convergence.csv' using (strcol(1) eq 'beam1d' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#27ae60' title 'photon beams beam1d, transient volume (slope -0.21)', \
     'convergence.csv' using (strcol(1) eq 'beam1d' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#27ae60' title 'photon beams beam1d, steady image (slope -0.25)', \
     'convergence.csv' using (strcol(1) eq 'point2d' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#8e44ad' title 'photon beams point2d, transient volume (slope -0.24)', \
     'convergence.csv' using (strcol(1) eq 'point2d' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#8e44ad' title 'photon beams point2d, steady image (slope -0.27)', \
     'convergence.csv' using (strcol(1) eq 'point3d' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#d68910' title 'photon beams point3d, transient volume (slope -0.30)', \
     'convergence.csv' using (strcol(1) eq 'point3d' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#d68910' title 'photon beams point3d, steady image (slope -0.30)', \
     'convergence.csv' using (strcol(1) eq 'beam2d+box' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#16a085' title 'photon beams beam2d+box, transient volume (slope -0.26)', \
     'convergence.csv' using (strcol(1) eq 'beam2d+box' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#16a085' title 'photon beams beam2d+box, steady image (slope -0.28)', \
     'convergence.csv' using (strcol(1) eq 'beam1d+box' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#7f8c8d' title 'photon beams beam1d+box, transient volume (slope -0.24)', \
     'convergence.csv' using (strcol(1) eq 'beam1d+box' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#7f8c8d' title 'photon beams beam1d+box, steady image (slope -0.26)', \
     'convergence.csv' using (strcol(1) eq 'point2d+box' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#e84393' title 'photon beams point2d+box, transient volume (slope -0.30)', \
     'convergence.csv' using (strcol(1) eq 'point2d+box' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#e84393' title 'photon beams point2d+box, steady image (slope -0.30)', \
     'convergence.csv' using (strcol(1) eq 'point3d+box' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#2c3e50' title 'photon beams point3d+box, transient volume (slope -0.32)', \
     'convergence.csv' using (strcol(1) eq 'point3d+box' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#2c3e50' title 'photon beams point3d+box, steady image (slope -0.30)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#2471a3' title 'path tracing, transient volume (slope -0.27)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#2471a3' title 'path tracing, steady image (slope -0.45)'
set terminal pngcairo size 900,640 font 'Helvetica,11' background rgb 'white'
set output 'convergence_l1.png'
replot
set output
