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
set title "cornell_medium.json, 64x64x64 bins, real time, delta emission" noenhanced
set terminal svg size 900,640 dynamic font 'Helvetica,13' background rgb 'white'
set output 'convergence.svg'
plot 'convergence.csv' using (strcol(1) eq 'beams' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#c0392b' title 'photon beams, transient volume (slope -0.26)', \
     'convergence.csv' using (strcol(1) eq 'beams' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#c0392b' title 'photon beams, steady image (slope -0.22)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):7 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#2471a3' title 'path tracing, transient volume (slope -0.04)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):8 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#2471a3' title 'path tracing, steady image (slope -0.05)', \
     0.033034 with lines dt 3 lw 1.5 lc rgb '#555555' title 'own error of the reference (transient volume)', \
     0.0197042 with lines dt 4 lw 1 lc rgb '#999999' title 'own error of the reference (steady image)'
set terminal pngcairo size 900,640 font 'Helvetica,11' background rgb 'white'
set output 'convergence.png'
replot
set output
set ylabel 'relative mean absolute error against the reference'
set terminal svg size 900,640 dynamic font 'Helvetica,13' background rgb 'white'
set output 'convergence_l1.svg'
plot 'convergence.csv' using (strcol(1) eq 'beams' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#c0392b' title 'photon beams, transient volume (slope -0.31)', \
     'convergence.csv' using (strcol(1) eq 'beams' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#c0392b' title 'photon beams, steady image (slope -0.27)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):14 with linespoints lw 2 pt 7 ps 0.5 lc rgb '#2471a3' title 'path tracing, transient volume (slope -0.33)', \
     'convergence.csv' using (strcol(1) eq 'pt' ? $3 : NaN):15 with linespoints lw 1.5 dt 2 pt 6 ps 0.5 lc rgb '#2471a3' title 'path tracing, steady image (slope -0.35)'
set terminal pngcairo size 900,640 font 'Helvetica,11' background rgb 'white'
set output 'convergence_l1.png'
replot
set output
