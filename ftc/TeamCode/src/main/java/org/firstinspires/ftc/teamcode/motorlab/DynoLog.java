/* motorlab: the log file motorlab reads (motorlab.io.read_ftc_log). */
package org.firstinspires.ftc.teamcode.motorlab;

import java.io.BufferedWriter;
import java.io.Closeable;
import java.io.File;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.OutputStreamWriter;
import java.nio.charset.Charset;
import java.util.Locale;
import java.util.Map;

/**
 * Writes seed 1's format, whitespace-separated {@code time_ms encoder_counts bus_voltage_V
 * shunt_current_A} (or {@code time_ms encoder_counts}), after leading {@code # key: value} lines naming
 * the experiment, motor, counts per revolution and gear ratio. Rows go out as they come, flushed every
 * {@link #FLUSH_ROWS} rows, so a run cut short still leaves its data on the controller.
 */
public final class DynoLog implements Closeable {
    public static final String POWER_COLUMNS = "time_ms encoder_counts bus_voltage_V shunt_current_A";
    public static final String TICK_COLUMNS = "time_ms encoder_counts";
    public static final int FLUSH_ROWS = 50;

    private final File file;
    private final BufferedWriter out;
    private final boolean power;
    private int rows;

    public DynoLog(File file, Map<String, String> fields, boolean power) throws IOException {
        File parent = file.getAbsoluteFile().getParentFile();
        if (parent != null && !parent.isDirectory() && !parent.mkdirs()) {
            throw new IOException("cannot create the folder " + parent);
        }
        this.file = file;
        this.power = power;
        out = new BufferedWriter(new OutputStreamWriter(new FileOutputStream(file), Charset.forName("UTF-8")));
        for (Map.Entry<String, String> field : fields.entrySet()) {
            String value = field.getValue().replace('\n', ' ').replace('\r', ' ');
            out.write("# " + field.getKey() + ": " + value + "\n");
        }
        out.write((power ? POWER_COLUMNS : TICK_COLUMNS) + "\n");
        out.flush();
    }

    public void write(Sample s) throws IOException {
        if (power) {
            out.write(String.format(Locale.US, "%.3f %d %.4f %.5f\n", s.time * 1e3, s.counts, s.voltage + 0.0, s.current + 0.0));
        } else {
            out.write(String.format(Locale.US, "%.3f %d\n", s.time * 1e3, s.counts));
        }
        if (++rows % FLUSH_ROWS == 0) {
            out.flush();
        }
    }

    public int rows() {
        return rows;
    }

    public File file() {
        return file;
    }

    @Override
    public void close() throws IOException {
        out.close();
    }
}
