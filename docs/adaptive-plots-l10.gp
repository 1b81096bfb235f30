# The level-10 sphere plot of docs/adaptive.md from a study run with even levels
# (`adaptive_bench --study=DIR --scene=sphere --finest=10 --adaptive-start=8 --even-levels
# --fine-ladder`).
# Usage: gnuplot -e "dir='DIR'; out='docs'" docs/adaptive-plots-l10.gp   (gnuplot-nox is enough)
set terminal pngcairo size 900,340 font ",10" noenhanced
set datafile separator ","
set grid
set output out."/adaptive-time-particles-l10.png"
set multiplot layout 1,2 title "Sheet dropped on a sphere: fixed levels 8 and 10 against adaptive (levels 8 to 10, even levels)"
set xlabel "simulated time (s)"
set key top left
set ylabel "CPU time so far (s)"
plot dir."/sphere_fixed_l10.csv" u 1:3 w l lw 2 t "fixed L10", \
     dir."/sphere_fixed_l8.csv" u 1:3 w l lw 2 t "fixed L8", \
     dir."/sphere_adaptive_0.707107mm.csv" u 1:3 w l t "adaptive 0.71 mm", \
     dir."/sphere_adaptive_0.5mm.csv" u 1:3 w l t "adaptive 0.5 mm"
set ylabel "particles"
set yrange [0:*]
set key center right
plot dir."/sphere_fixed_l10.csv" u 1:4 w l lw 2 t "fixed L10", \
     dir."/sphere_fixed_l8.csv" u 1:4 w l lw 2 t "fixed L8", \
     dir."/sphere_adaptive_0.707107mm.csv" u 1:4 w l t "adaptive 0.71 mm", \
     dir."/sphere_adaptive_0.5mm.csv" u 1:4 w l t "adaptive 0.5 mm"
unset multiplot
