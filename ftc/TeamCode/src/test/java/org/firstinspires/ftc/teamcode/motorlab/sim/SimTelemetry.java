/* motorlab JVM test: a Telemetry that keeps the last screen (and prints it when asked). */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import java.util.ArrayList;
import java.util.List;
import java.util.Locale;
import org.firstinspires.ftc.robotcore.external.Telemetry;

/** Collects caption/value lines; update() makes them the screen and starts a new one. */
public final class SimTelemetry implements Telemetry {
    private final boolean print;
    private List<String> pending = new ArrayList<String>();
    private List<String> screen = new ArrayList<String>();
    public int updates = 0;

    public SimTelemetry(boolean print) {
        this.print = print;
    }

    public List<String> screen() {
        return screen;
    }

    private final class SimItem implements Item, Line {
        private String caption;
        private final int index;

        SimItem(String caption, String value) {
            this.caption = caption;
            index = pending.size();
            pending.add(caption + " : " + value);
        }

        @Override
        public String getCaption() {
            return caption;
        }

        @Override
        public Item setCaption(String caption) {
            this.caption = caption;
            return this;
        }

        @Override
        public Item setValue(String format, Object... args) {
            pending.set(index, caption + " : " + String.format(Locale.US, format, args));
            return this;
        }

        @Override
        public Item setValue(Object value) {
            pending.set(index, caption + " : " + value);
            return this;
        }

        @Override
        public Item setRetained(Boolean retained) {
            return this;
        }

        @Override
        public boolean isRetained() {
            return false;
        }

        @Override
        public Item addData(String caption, String format, Object... args) {
            return SimTelemetry.this.addData(caption, format, args);
        }

        @Override
        public Item addData(String caption, Object value) {
            return SimTelemetry.this.addData(caption, value);
        }
    }

    @Override
    public Item addData(String caption, String format, Object... args) {
        return new SimItem(caption, String.format(Locale.US, format, args));
    }

    @Override
    public Item addData(String caption, Object value) {
        return new SimItem(caption, String.valueOf(value));
    }

    @Override
    public void clear() {
        pending.clear();
    }

    @Override
    public void clearAll() {
        pending.clear();
        screen.clear();
    }

    @Override
    public boolean update() {
        screen = pending;
        pending = new ArrayList<String>();
        updates++;
        if (print) {
            for (String line : screen) {
                System.err.println("telemetry | " + line);
            }
        }
        return true;
    }

    @Override
    public Line addLine() {
        return new SimItem("", "");
    }

    @Override
    public Line addLine(String lineCaption) {
        return new SimItem(lineCaption, "");
    }

    @Override
    public boolean isAutoClear() {
        return true;
    }

    @Override
    public void setAutoClear(boolean autoClear) {
    }

    @Override
    public int getMsTransmissionInterval() {
        return 250;
    }

    @Override
    public void setMsTransmissionInterval(int msTransmissionInterval) {
    }
}
